"""Physical and numerical settings of the simulated platform, in one validated frozen dataclass."""

from __future__ import annotations

from dataclasses import dataclass, fields

from tooltransfer.errors import InputError
from tooltransfer.validation import check_positive


@dataclass(frozen=True)
class SimConfig:
    """Settings of the simulated platform (SI units).

    Physics (see :mod:`tooltransfer.tools.sim.mjcf` for why each numerical setting has its value):

    Attributes:
        timestep: physics step [s]; 1-2 ms give the same push.
        puck_mass: mass of the puck [kg].
        puck_radius: radius of the puck [m] (Table II: 17.5 mm).
        puck_height: height of the puck [m].
        table_friction: sliding friction coefficient between the puck and the table (and the
            obstacles).
        tool_friction: sliding friction coefficient between the tool and the puck. 0.8 keeps the
            faces' push cones (theta_b = pi/6) inside the friction cone (atan 0.8 = 39 deg), so a
            push inside the cone sticks, as the paper's quasi-static model assumes.
        contact_timeconst: time constant of the contact constraint [s] (MuJoCo ``solref[0]``).
        contact_dampratio: damping ratio of the contact constraint (``solref[1]``); 1 is critical.
        tool_gap: height [m] of the tool's lower side above the table (it must not touch it).
        tool_thickness: height [m] of the tool's prisms; the tool spans
            ``[tool_gap, tool_gap + tool_thickness]`` and so meets the puck's side.
        kp: joint position gain [N m/rad] of the PD tracking.
        kv: joint velocity gain [N m s/rad] of the PD tracking.
        torque_limit: largest PD torque on each joint [N m]: the Omni's peak force of 3.3 N
            (datasheet, at the nominal position) at its reach of about 0.27 m; in free motion and
            pushing the puck the PD torques stay below 0.02 N m.
    """

    timestep: float = 0.001
    puck_mass: float = 0.02
    puck_radius: float = 0.0175
    puck_height: float = 0.010
    table_friction: float = 0.3
    tool_friction: float = 0.8
    contact_timeconst: float = 0.005
    contact_dampratio: float = 1.0
    tool_gap: float = 0.001
    tool_thickness: float = 0.010
    kp: float = 40.0
    kv: float = 0.8
    torque_limit: float = 0.9

    def __post_init__(self) -> None:
        for f in fields(self):
            object.__setattr__(self, f.name, check_positive(getattr(self, f.name), f.name))
        if self.timestep > 0.005:
            raise InputError("timestep", "a physics step of at most 5 ms (1-2 ms recommended)", self.timestep)
        if self.contact_timeconst < 2.0 * self.timestep:
            raise InputError(
                "contact_timeconst",
                f"at least two physics steps ({2.0 * self.timestep} s) or MuJoCo clamps it",
                self.contact_timeconst,
            )
        if self.tool_gap >= self.puck_height:
            raise InputError("tool_gap", f"less than the puck's height {self.puck_height} m", self.tool_gap)
