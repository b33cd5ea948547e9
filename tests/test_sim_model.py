"""The simulated platform's MuJoCo model: it compiles for every library tool, its kinematics equal
the DH model's, the tool stays level at table height, only the intended contacts exist, the
measured contact settings are in force, and settings are validated."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
import shapely

from tooltransfer.errors import InputError
from tooltransfer.tools import Disc, load_tool
from tooltransfer.tools.library import library_names
from tooltransfer.tools.omni.ik import tool_pose_world
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.sim import SimConfig, SimModel, SimPlatform, build_mjcf
from tooltransfer.tools.sim.mjcf import ARM_JOINTS, LEVEL_JOINTS, TCP_BODY, TOOL_BODY, tool_piece_names


@pytest.mark.parametrize("name", library_names())
def test_model_compiles_and_its_kinematics_equal_the_dh_model(name: str) -> None:
    tool = load_tool(name)
    plat = OmniPlatform(a_t=tool.a_t, base_xy=(0.01, -0.02), base_yaw=1.4, table_height=0.005)
    sm = SimModel.build(tool, plat)
    m = sm.model
    d = mujoco.MjData(m)
    assert len(tool_piece_names(tool)) == len(tool.convex_pieces) >= 1
    rng = np.random.default_rng(0)
    lo, hi = np.array(plat.limits.lower), np.array(plat.limits.upper)
    for q in rng.uniform(lo, hi, (20, 3)):
        sm.set_configuration(d, np.array([0.0, 0.3]), q)
        T = tool_pose_world(plat, q)
        xm = d.body(TOOL_BODY).xmat.reshape(3, 3)
        assert np.abs(d.body(TCP_BODY).xpos - T[:3, 3]).max() < 1e-9  # tool centre point, 3-D [m]
        heading = np.arctan2(xm[1, 0], xm[0, 0])
        assert abs(np.angle(np.exp(1j * (heading - plat.heading(q[0]))))) < 1e-9  # heading follows q1
        assert np.allclose(xm[:, 2], [0, 0, 1], atol=1e-9)  # the tool stays level


def _tool_vertices(sim: SimPlatform) -> np.ndarray:
    """World vertices (K, 3) [m] of the tool's prisms in the current state."""
    m, d = sim.model, sim.data
    out = []
    for name in tool_piece_names(sim.tool):
        g = m.geom(name)
        a, n = m.mesh_vertadr[g.dataid[0]], m.mesh_vertnum[g.dataid[0]]
        out.append(d.geom(g.id).xpos + m.mesh_vert[a : a + n] @ d.geom(g.id).xmat.reshape(3, 3).T)
    return np.vstack(out)


def test_the_tool_plane_is_the_tool_frame_of_the_outline() -> None:
    """The prisms' vertices land where the recorded tool pose (a Pose2D) puts the outline's pieces."""
    from tooltransfer.tools.pose import Pose2D

    tool = load_tool("l_shape")
    sim = SimPlatform(tool)
    sim.reset([0.0, 0.3], q0=[0.4, 0.5, 1.0])
    pose = Pose2D(*sim.observe()[1])
    expect = np.vstack([pose.apply(np.asarray(p.exterior.coords)[:-1]) for p in tool.convex_pieces])
    for w in _tool_vertices(sim)[:, :2]:
        assert np.min(np.hypot(*(expect - w).T)) < 1e-6  # mesh vertices are stored in float32


def test_the_tool_sits_just_above_the_table_and_meets_the_puck_side() -> None:
    cfg = SimConfig()
    sim = SimPlatform(load_tool("finger"), config=cfg)
    for xy in ([0.0, 0.15], [-0.08, 0.12], [0.1, 0.18]):
        sim.reset([0.0, 0.3], tool_xy=xy)
        z = _tool_vertices(sim)[:, 2]
        assert z.min() == pytest.approx(cfg.tool_gap, abs=1e-6)
        assert z.max() == pytest.approx(cfg.tool_gap + cfg.tool_thickness, abs=1e-6)
    assert 0 < cfg.tool_gap < cfg.puck_height  # so it overlaps the puck's side and clears the table


def test_only_tool_puck_puck_table_and_puck_obstacle_contacts_can_exist() -> None:
    tool = load_tool("t_shape")
    obstacles = [Disc(np.array([0.1, 0.1]), 0.02), shapely.Polygon([(0, 0), (0.05, 0), (0.05, 0.05), (0.04, 0.01)])]
    m = SimModel.build(tool, OmniPlatform(a_t=tool.a_t), obstacles).model
    puck = m.geom("puck").id
    colliding = set()
    for i in range(m.ngeom):
        for j in range(i + 1, m.ngeom):
            if m.geom_bodyid[i] == m.geom_bodyid[j]:
                continue
            if (m.geom_contype[i] & m.geom_conaffinity[j]) or (m.geom_contype[j] & m.geom_conaffinity[i]):
                colliding.add((i, j))
    assert colliding and all(puck in pair for pair in colliding)
    others = {m.geom(j if i == puck else i).name for i, j in colliding}
    assert others == {"table", *tool_piece_names(tool), "obstacle0", "obstacle1_0", "obstacle1_1"}


def test_the_measured_contact_settings_are_in_force() -> None:
    tool = load_tool("finger")
    cfg = SimConfig()
    m = SimModel.build(tool, OmniPlatform(a_t=tool.a_t), config=cfg).model
    assert m.opt.timestep == 0.001
    assert m.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    assert m.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    assert m.opt.solver == mujoco.mjtSolver.mjSOL_NEWTON
    assert m.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_MULTICCD  # on by default in MuJoCo 4.0
    for name in ("puck", "table", *tool_piece_names(tool)):
        assert tuple(m.geom(name).solref) == (cfg.contact_timeconst, 1.0)
    assert m.geom("table").priority[0] > m.geom("puck").priority[0]
    assert m.geom(tool_piece_names(tool)[0]).priority[0] > m.geom("puck").priority[0]
    assert m.geom(tool_piece_names(tool)[0]).friction[0] == cfg.tool_friction
    assert all(m.body_gravcomp[m.body(b).id] == 1.0 for b in ("link1", "link2", "link3", TCP_BODY, TOOL_BODY))
    for j in ARM_JOINTS:  # the PD torque saturates as the Omni's motors do
        assert m.jnt_actfrclimited[m.joint(j).id] and tuple(m.jnt_actfrcrange[m.joint(j).id]) == (
            -cfg.torque_limit, cfg.torque_limit)
    assert m.nu == 6 and set(ARM_JOINTS) <= {m.joint(i).name for i in range(m.njnt)}
    assert set(LEVEL_JOINTS) <= {m.joint(i).name for i in range(m.njnt)}


def test_the_mjcf_text_is_deterministic() -> None:
    tool = load_tool("trapezoid")
    plat = OmniPlatform(a_t=tool.a_t)
    assert build_mjcf(tool, plat) == build_mjcf(tool, plat)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [({"timestep": 0.0}, "timestep"), ({"timestep": 0.01}, "timestep"), ({"tool_gap": 0.02}, "tool_gap"),
     ({"contact_timeconst": 0.001}, "contact_timeconst"), ({"puck_mass": float("nan")}, "puck_mass")],
)
def test_bad_settings_are_refused_naming_the_field(kwargs: dict, field: str) -> None:
    with pytest.raises(InputError) as err:
        SimConfig(**kwargs)
    assert err.value.field == field


def test_bad_constructor_arguments_are_refused() -> None:
    tool = load_tool("finger")
    with pytest.raises(InputError, match="config="):
        SimPlatform(tool, None, SimConfig())  # type: ignore[arg-type]
    with pytest.raises(InputError, match="tool"):
        SimPlatform("finger")  # type: ignore[arg-type]
    with pytest.raises(InputError) as err:
        SimPlatform(tool, obstacles=[Disc(np.array([0.1, 0.1]), 0.02), (0.1, 0.2)])  # type: ignore[list-item]
    assert err.value.field == "obstacles[1]"
