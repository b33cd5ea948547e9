"""The simulated platform's MuJoCo model, written as MJCF text from the DH table, the tool and the scene.

Kinematics. Each DH row ``Rz(theta) Tz(d) Tx(a) Rx(alpha)`` of :mod:`tooltransfer.tools.omni.dh` becomes a body
whose hinge turns about its local z (the joint), with the next body at ``(a, 0, d)`` turned by
``Rx(alpha)``; the tool centre point is the origin of the tool-row body, exactly as in
:func:`tooltransfer.tools.omni.dh.forward_kinematics`. The Omni base sits at the platform's ``base_xy`` and
``base_yaw``, ``table_height`` below its frame (:class:`tooltransfer.tools.omni.platform.OmniPlatform`); the
joints have the platform's limits as mechanical stops.

The tool. The Omni's last three joints are fixed, so the tool turns in the table plane with q1
only (docs/design.md section 7): a planar tool stays flat on the table while the shoulder and the elbow
move. The tool body hangs from the tool centre point on two hinges about the arm-plane normal held
by joint equalities at ``-q2`` and ``-q3`` (a parallelogram, as the real holder keeps the tool
level), so its orientation is ``Rz(base_yaw + q1 - pi/2)`` (:meth:`OmniPlatform.heading`) whatever
the arm's pitch. Its outline's convex pieces (:attr:`tooltransfer.tools.model.Tool.convex_pieces`) become prisms
from ``tool_gap`` to ``tool_gap + tool_thickness`` above the table, so the tool meets the puck's side
and never the table.

Collisions. Only tool-puck, puck-table and puck-obstacle contacts exist (contype/conaffinity
bits): the links are visual only, and the tool passes through obstacles (the planner keeps it
clear of them geometrically). Non-convex obstacle polygons are split into convex pieces.

Contact settings that matter with MuJoCo 4.0 on a forward push of the puck with tool 1's upper face
(figures in ``benchmarks/README.md``):

* ``<flag multiccd="disable"/>``: with it on, contacts on the prism's edges get a wrong normal
  (a large final error and penetration).
* ``cone="elliptic"``: pyramidal cones let the puck slide off the tool.
* contact ``solref="0.005 1"``: damping ratio 1 (lower ratios give large errors) with a 5 ms time
  constant.
* ``timestep`` 1 ms (1-2 ms give the same push), ``integrator="implicitfast"`` (stable with the
  velocity actuators' damping), ``solver="Newton"``.
* ``priority`` on the table, obstacle and tool geoms, so their friction is the one used against
  the puck (not the larger of the two geoms').

The pyramidal cones matter most (the puck slides on the face); the other settings move the final
puck by up to a few millimetres (the sideways sweep's end is sensitive, see tests/test_sim_push.py),
and priority changes nothing while the puck's own friction equals the table's.

The arm: gravity compensation on every moving body (``gravcomp="1"``), and a position plus a
velocity actuator per joint: ``tau = kp (q_ref - q) + kv (qd_ref - qd)``, PD tracking of a joint
reference as the real device after dynamics compensation, the sum clamped to the joint's
``actuatorfrcrange`` (``SimConfig.torque_limit``) as the Omni's motors saturate: without it a
tool squeezing the puck against a wall pushed with 12 N and the puck went 3.3 mm into the wall
(0.4 mm with it).

Recording: sensors for the joints, the tool centre point and heading, the puck's pose, and per
tool piece its deepest contact with the puck (``contact`` sensor: count, signed distance,
position), so a whole execution runs in :func:`mujoco.rollout.rollout` and is read from its
sensor data.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.tools.decompose import convex_decomposition
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc, Obstacle
from tooltransfer.tools.omni.dh import D1, D_TOOL, L1, L2, THETA_TOOL
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.sim.config import SimConfig

#: Names of the model's joints driven by the PD actuators, in DH order.
ARM_JOINTS = ("q1", "q2", "q3")
#: Names of the two hinges keeping the tool level (held at -q2 and -q3 by joint equalities).
LEVEL_JOINTS = ("level2", "level3")
#: Body whose origin is the tool centre point (the DH tool frame's origin).
TCP_BODY = "tcp_row"
#: Body carrying the tool's prisms; its frame is the planar tool frame of :mod:`tooltransfer.tools.model`.
TOOL_BODY = "tool_plane"
PUCK = "puck"

# contype / conaffinity bits: the puck collides with everything that has bit 1; the others with it only
_PUCK_BITS = 'contype="1" conaffinity="1"'
_STATIC_BITS = 'contype="1" conaffinity="0"'
_VISUAL_BITS = 'contype="0" conaffinity="0"'


def _num(v: float) -> str:
    return f"{float(v):.17g}"


def _quat_x(angle: float) -> str:
    return f"{_num(np.cos(angle / 2))} {_num(np.sin(angle / 2))} 0 0"


def _quat_z(angle: float) -> str:
    return f"{_num(np.cos(angle / 2))} 0 0 {_num(np.sin(angle / 2))}"


def _rz(a: float) -> NDArray[np.float64]:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rx(a: float) -> NDArray[np.float64]:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _mat_to_quat(m: NDArray[np.float64]) -> NDArray[np.float64]:
    """Unit quaternion (w, x, y, z) of a rotation matrix (3, 3)."""
    w = np.sqrt(max(0.0, 1.0 + m[0, 0] + m[1, 1] + m[2, 2])) / 2
    x = np.copysign(np.sqrt(max(0.0, 1.0 + m[0, 0] - m[1, 1] - m[2, 2])) / 2, m[2, 1] - m[1, 2])
    y = np.copysign(np.sqrt(max(0.0, 1.0 - m[0, 0] + m[1, 1] - m[2, 2])) / 2, m[0, 2] - m[2, 0])
    z = np.copysign(np.sqrt(max(0.0, 1.0 - m[0, 0] - m[1, 1] + m[2, 2])) / 2, m[1, 0] - m[0, 1])
    q = np.array([w, x, y, z])
    return q / np.linalg.norm(q)


def _prism_mesh(name: str, piece: shapely.Polygon, z0: float, z1: float) -> str:
    """A convex mesh asset: the polygon's vertices at heights ``z0`` and ``z1`` [m]."""
    ring = np.asarray(shapely.geometry.polygon.orient(piece, 1.0).exterior.coords)[:-1]
    verts = " ".join(_num(v) for z in (z0, z1) for x, y in ring for v in (x, y, z))
    return f'<mesh name="{name}" vertex="{verts}"/>'


def tool_piece_names(tool: Tool) -> tuple[str, ...]:
    """Geom names of the tool's convex pieces, in the order of :attr:`Tool.convex_pieces`."""
    return tuple(f"tool_piece{i}" for i in range(len(tool.convex_pieces)))


def _obstacles(obstacles: Sequence[Obstacle], height: float, friction: str) -> tuple[list[str], list[str]]:
    assets, geoms = [], []
    look = f'rgba="0.8 0.3 0.3 1" priority="1" friction="{friction}" {_STATIC_BITS}'
    for i, o in enumerate(obstacles):
        if isinstance(o, Disc):
            geoms.append(
                f'<geom name="obstacle{i}" type="cylinder" size="{_num(o.radius)} {_num(height / 2)}" '
                f'pos="{_num(o.centre[0])} {_num(o.centre[1])} {_num(height / 2)}" {look}/>'
            )
        else:
            for j, piece in enumerate(convex_decomposition(o)):
                assets.append(_prism_mesh(f"obstacle{i}_{j}", piece, 0.0, height))
                geoms.append(f'<geom name="obstacle{i}_{j}" type="mesh" mesh="obstacle{i}_{j}" {look}/>')
    return assets, geoms


def _arm_xml(platform: OmniPlatform, c: SimConfig, tool_geoms: str) -> str:
    """The Omni's body chain (MJCF ``<body name="base">``, indented for the worldbody): three
    position-limited, torque-saturated revolute joints, the tool row and the two level-keeping hinges
    carrying the tool's geoms ``tool_geoms``, placed at the platform's base pose."""
    # the planar tool frame in the tool-row body once the two level-keeping hinges have acted:
    # base-frame orientation Rz(q1) Rx(-pi/2) Rz(theta_t) G must equal Rz(q1 - pi/2)
    g = (_rx(-np.pi / 2) @ _rz(THETA_TOOL)).T @ _rz(-np.pi / 2)
    gq = " ".join(_num(v) for v in _mat_to_quat(g))
    lo, hi = platform.limits.lower, platform.limits.upper
    torque = f'actuatorfrcrange="{_num(-c.torque_limit)} {_num(c.torque_limit)}"'
    limits = [f'range="{_num(lo[j])} {_num(hi[j])}" {torque}' for j in range(3)]
    bx, by = platform.base_xy
    link = f'{_VISUAL_BITS} rgba="0.6 0.6 0.6 0.5"'
    inertia = 'mass="0.08" diaginertia="2e-4 2e-4 2e-4"'
    small = 'pos="0 0 0" mass="0.005" diaginertia="1e-6 1e-6 1e-6"'
    at = f'pos="{_num(bx)} {_num(by)} {_num(-platform.table_height)}" quat="{_quat_z(platform.base_yaw)}"'
    return f"""<body name="base" {at}>
      <body name="link1" gravcomp="1">
        <joint name="q1" axis="0 0 1" {limits[0]}/>
        <inertial pos="0 0 0.05" {inertia}/>
        <geom type="capsule" fromto="0 0 0 0 0 {_num(D1)}" size="0.012" {link}/>
        <body name="link2" pos="0 0 {_num(D1)}" quat="{_quat_x(-np.pi / 2)}" gravcomp="1">
          <joint name="q2" axis="0 0 1" {limits[1]}/>
          <inertial pos="{_num(L1 / 2)} 0 0" {inertia}/>
          <geom type="capsule" fromto="0 0 0 {_num(L1)} 0 0" size="0.008" {link}/>
          <body name="link3" pos="{_num(L1)} 0 0" gravcomp="1">
            <joint name="q3" axis="0 0 1" {limits[2]}/>
            <inertial pos="{_num(L2 / 2)} 0 0" {inertia}/>
            <geom type="capsule" fromto="0 0 0 {_num(L2)} 0 0" size="0.006" {link}/>
            <body name="tcp" pos="{_num(L2)} 0 0" quat="{_quat_z(THETA_TOOL)}" gravcomp="1">
              <inertial {small}/>
              <geom type="capsule" fromto="0 0 0 {_num(platform.a_t)} 0 {_num(D_TOOL)}" size="0.003" {link}/>
              <body name="{TCP_BODY}" pos="{_num(platform.a_t)} 0 {_num(D_TOOL)}" gravcomp="1">
                <inertial {small}/>
                <body name="level2" gravcomp="1">
                  <joint name="level2" axis="0 0 1"/>
                  <inertial {small}/>
                  <body name="tool" gravcomp="1">
                    <joint name="level3" axis="0 0 1"/>
                    <inertial {small}/>
                    <body name="{TOOL_BODY}" quat="{gq}" gravcomp="1">
                      {tool_geoms}
                    </body>
                  </body>
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>"""


def _drives_xml(c: SimConfig, contact_sensors: str) -> str:
    """The MJCF ``<equality>`` (the level-keeping hinges follow the arm's joints), ``<actuator>``
    (PD: position gain ``kp``, velocity gain ``kv``) and ``<sensor>`` sections (joints, tool row,
    tool axes, puck pose and the ``contact_sensors``), indented for the document's top level."""
    return f"""<equality>
    <joint joint1="level2" joint2="q2" polycoef="0 -1 0 0 0" solref="0.002 1"/>
    <joint joint1="level3" joint2="q3" polycoef="0 -1 0 0 0" solref="0.002 1"/>
  </equality>
  <actuator>
    <position name="p1" joint="q1" kp="{_num(c.kp)}"/>
    <position name="p2" joint="q2" kp="{_num(c.kp)}"/>
    <position name="p3" joint="q3" kp="{_num(c.kp)}"/>
    <velocity name="v1" joint="q1" kv="{_num(c.kv)}"/>
    <velocity name="v2" joint="q2" kv="{_num(c.kv)}"/>
    <velocity name="v3" joint="q3" kv="{_num(c.kv)}"/>
  </actuator>
  <sensor>
    <jointpos name="q1" joint="q1"/>
    <jointpos name="q2" joint="q2"/>
    <jointpos name="q3" joint="q3"/>
    <framepos name="tcp" objtype="xbody" objname="{TCP_BODY}"/>
    <framexaxis name="tool_x" objtype="xbody" objname="{TOOL_BODY}"/>
    <framezaxis name="tool_z" objtype="xbody" objname="{TOOL_BODY}"/>
    <framepos name="puck_pos" objtype="xbody" objname="{PUCK}"/>
    <framequat name="puck_quat" objtype="xbody" objname="{PUCK}"/>
    {contact_sensors}
  </sensor>"""


def build_mjcf(
    tool: Tool, platform: OmniPlatform, obstacles: Sequence[Obstacle] = (), config: SimConfig | None = None
) -> str:
    """The MJCF text of the Omni carrying ``tool``, with the puck and ``obstacles`` on the table.

    Args:
        tool: the tool (its convex pieces become the colliding prisms).
        platform: the Omni's placement, joint limits and ``a_t`` (the tool-row length used).
        obstacles: discs and polygons on the table (world frame [m]), static, twice the puck's height.
        config: physical settings (default :class:`SimConfig`).

    Returns:
        The MJCF document (compile it with ``mujoco.MjModel.from_xml_string``). The puck starts at
        the origin; :class:`tooltransfer.tools.sim.platform.SimPlatform` places it.
    """
    c = config or SimConfig()
    z0, z1 = c.tool_gap, c.tool_gap + c.tool_thickness
    pieces = tool.convex_pieces
    names = tool_piece_names(tool)
    assets = [_prism_mesh(n, p, z0, z1) for n, p in zip(names, pieces, strict=True)]
    tool_fric = f"{_num(c.tool_friction)} 0.005 0.0001"
    tool_geoms = "\n".join(
        f'<geom name="{n}" type="mesh" mesh="{n}" priority="1" friction="{tool_fric}" '
        f'rgba="0.3 0.5 0.8 1" mass="0.002" {_STATIC_BITS}/>'
        for n in names
    )
    table_fric = f"{_num(c.table_friction)} 0.005 0.0001"
    obstacle_assets, obstacle_geoms = _obstacles(obstacles, 2.0 * c.puck_height, table_fric)
    assets += obstacle_assets
    contact_sensors = "\n".join(
        f'<contact name="touch_{n}" geom1="{n}" geom2="{PUCK}" num="1" data="found dist pos" reduce="mindist"/>'
        for n in names
    )
    nl = "\n"
    return f"""<mujoco model="omni_{tool.name}">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{_num(c.timestep)}" integrator="implicitfast" solver="Newton" cone="elliptic"
          gravity="0 0 -9.81">
    <flag multiccd="disable"/>
  </option>
  <default>
    <geom solref="{_num(c.contact_timeconst)} {_num(c.contact_dampratio)}" solimp="0.95 0.99 0.001"/>
    <joint armature="0.001" damping="0.01"/>
  </default>
  <asset>
    {nl.join(assets)}
  </asset>
  <worldbody>
    <geom name="table" type="plane" size="1 1 0.01" priority="1" friction="{table_fric}"
          rgba="0.9 0.9 0.85 1" {_STATIC_BITS}/>
    {nl.join(obstacle_geoms)}
    <body name="{PUCK}" pos="0 0 {_num(c.puck_height / 2)}">
      <freejoint name="{PUCK}"/>
      <geom name="{PUCK}" type="cylinder" size="{_num(c.puck_radius)} {_num(c.puck_height / 2)}"
            mass="{_num(c.puck_mass)}" friction="{table_fric}" rgba="0.2 0.2 0.2 1" {_PUCK_BITS}/>
    </body>
    {_arm_xml(platform, c, tool_geoms)}
  </worldbody>
  {_drives_xml(c, contact_sensors)}
</mujoco>
"""
