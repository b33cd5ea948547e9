"""The quasi-static push model (tooltransfer.tools.pushing): the contact law, the forward simulator, the inverse,
and their agreement with the MuJoCo platform (docs/design.md section 10)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tooltransfer.tools.library import load_tool, tool_from_dict
from tooltransfer.tools.omni.heading import heading
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.pushing.forward import simulate
from tooltransfer.tools.pushing.inverse import FaceGeometry, push_tool_path
from tooltransfer.tools.pushing.mechanics import SLIDE, STICK, PushMechanics, object_displacement, pusher_velocity

R = 0.0175

BAR = tool_from_dict({
    "name": "bar", "a_t": 0.03,
    "outline": [[-0.05, -0.02], [0.05, -0.02], [0.05, 0.0], [-0.05, 0.0]],
    "faces": [{"name": "top", "segment": [[-0.05, 0.0], [0.05, 0.0]], "push_angle": "pi/2", "theta_b": 1.2}],
})
"""A 100 mm flat face (normal +y in the tool frame), long enough that the contact never leaves it."""

SEEDED = settings(max_examples=40, deadline=None, derandomize=True)


def _straight(angle: float, length: float = 0.03, n: int = 301) -> np.ndarray:
    """Tool poses (n, 3): the bar moving ``length`` [m] at ``angle`` [rad] off its face's normal, yaw 0."""
    s = np.linspace(0.0, length, n)
    return np.column_stack([s * np.sin(angle), s * np.cos(angle), np.zeros(n)])


@SEEDED
@given(angle=st.floats(-1.3, 1.3), mu=st.floats(1e-4, 1e-3), c=st.floats(0.3, 1.2))
def test_frictionless_contact_moves_the_object_along_the_normal(angle: float, mu: float, c: float) -> None:
    trace = simulate(BAR, _straight(angle), np.array([0.0, R]), R, PushMechanics(mu, c))
    move = trace.final - np.array([0.0, R])
    assert move[1] > 0.005
    assert abs(np.degrees(np.arctan2(move[0], move[1]))) <= np.degrees(np.arctan(mu)) + 1e-6


@SEEDED
@given(mu=st.floats(0.2, 1.5), c=st.floats(0.3, 1.2), side=st.sampled_from([-1.0, 1.0]),
       frac=st.floats(0.05, 0.95))
def test_sticking_and_sliding_on_either_side_of_the_boundary(mu: float, c: float, side: float, frac: float) -> None:
    mech = PushMechanics(mu, c)
    n = np.array([[0.0, 1.0]])
    # inside the boundary |b| <= mu kappa a: sticking, tan(phi_c) = tan(phi_p) / kappa
    b = side * frac * mu * mech.kappa
    d, mode = object_displacement(np.array([1.0]), np.array([b]), n, mech)
    assert mode[0] == STICK
    assert np.isclose(-d[0, 0] / d[0, 1], b / mech.kappa, rtol=1e-12)  # t = J n = (-1, 0)
    # beyond it: sliding on the friction cone's edge, whatever the excess
    b = side * mu * mech.kappa / frac
    d, mode = object_displacement(np.array([1.0]), np.array([b]), n, mech)
    assert mode[0] == SLIDE
    assert np.isclose(np.arctan2(abs(d[0, 0]), d[0, 1]), np.arctan(mu), rtol=1e-12)
    assert np.sign(-d[0, 0]) == side
    # pulling away: no motion
    d, mode = object_displacement(np.array([-1.0]), np.array([b]), n, mech)
    assert mode[0] == 0 and np.all(d == 0.0)


@SEEDED
@given(vx=st.floats(-0.5, 0.5), c=st.floats(0.3, 1.2))
def test_pusher_velocity_inverts_the_sticking_law(vx: float, c: float) -> None:
    mech = PushMechanics(0.9, c)
    n = np.array([[0.0, 1.0]])
    v = np.array([[vx, 1.0]])
    p = pusher_velocity(v, n, mech)
    d, mode = object_displacement(p[:, 1], -p[:, 0], n, mech)  # slip along t = (-1, 0)
    if mode[0] == STICK:
        assert np.allclose(d, v, atol=1e-12)
    else:
        assert abs(vx) > mech.mu


def test_straight_pushes_follow_the_closed_form() -> None:
    """tan(phi_c) = tan(phi_p) / kappa while sticking, the contact sliding along the face by
    (1 - 1/kappa) sin(phi_p) per unit of tool travel."""
    mech = PushMechanics(0.8, 0.59)
    for deg in (0, 10, 20, 30, 40, 50, 60):
        a = np.radians(deg)
        trace = simulate(BAR, _straight(a, 0.045, 451), np.array([0.0, R]), R, mech)
        move = trace.final - np.array([0.0, R])
        assert np.isclose(np.arctan2(move[0], move[1]), np.arctan(np.tan(a) / mech.kappa), atol=1e-6)
        slide = abs(trace.contact_tool[-1, 0] - trace.contact_tool[1, 0]) / 0.045
        assert np.isclose(slide, np.sin(a) * (1 - 1 / mech.kappa), atol=2e-3)
        assert set(trace.face[1:]) == {"top"}


def test_a_tool_moving_away_leaves_the_object() -> None:
    mech = PushMechanics(0.8, 0.59)
    trace = simulate(BAR, _straight(np.pi, 0.02), np.array([0.0, R]), R, mech)
    assert np.allclose(trace.object_xy, [0.0, R])
    assert all(e.mode == "free" for e in trace.events)


def test_a_corner_pushes_along_the_line_through_the_centre() -> None:
    """Point contact at a vertex: without friction the centre moves along the vertex-centre line."""
    corner = np.array([0.05, 0.0])
    start = corner + R * np.array([np.cos(0.6), np.sin(0.6)])
    trace = simulate(BAR, _straight(0.0, 0.005, 101), start, R, PushMechanics(1e-4, 0.6))
    move = trace.object_xy[5] - start
    line = (start - corner) / R
    assert np.dot(move, line) / np.linalg.norm(move) > 0.999


def _path_on_omni(tool_name: str, face: str, seed: int) -> tuple:
    """A push along the face's normal at the heading the Omni imposes, with a smooth sideways
    wobble, for the inverse model (contact kept on the face by its construction)."""
    rng = np.random.default_rng(seed)
    tool = load_tool(tool_name)
    plat = OmniPlatform(a_t=tool.a_t)
    g = FaceGeometry.of(tool, face)
    c = np.zeros((300, 2))
    c[0] = (rng.uniform(-0.03, 0.05), rng.uniform(0.13, 0.17))
    amp = rng.uniform(-0.02, 0.02)
    for k in range(299):
        psi = heading(plat, c[k:k + 1] - (g.start + R * g.normal)[None])[0]
        n = np.array([np.cos(psi) * g.normal[0] - np.sin(psi) * g.normal[1],
                      np.sin(psi) * g.normal[0] + np.cos(psi) * g.normal[1]])
        t = np.array([-n[1], n[0]])
        c[k + 1] = c[k] + 1e-4 * n + 1e-4 * amp * np.cos(np.pi * k / 299) * t
    return tool, plat, g, c


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize(("tool_name", "face"), [("slope", "inclined"), ("trapezoid", "left"), ("t_shape", "top")])
def test_forward_of_inverse_reproduces_the_wanted_path(tool_name: str, face: str, seed: int) -> None:
    tool, plat, g, c = _path_on_omni(tool_name, face, seed)
    mech = PushMechanics(0.8, 0.59)
    fp = push_tool_path(tool, face, c, R, mech, 0.5 * (g.lo + g.hi), platform=plat)
    if fp.edge_margin < 0 or not fp.sticks:
        pytest.skip("this draw leaves the face or the friction cone: not a path the face can push")
    trace = simulate(tool, fp.tool_pose, c[0], R, mech)
    assert np.max(np.linalg.norm(trace.object_xy - c, axis=1)) < 1e-5  # 0.01 mm over a 30 mm push
    on_face = np.array([f == face for f in trace.face[1:]])
    assert on_face.all()
    assert np.max(np.abs(trace.face_s[1:] * g.length - fp.s[1:])) < 5e-5
    # the Omni's heading holds along the tool path
    assert np.allclose(fp.tool_pose[:, 2], heading(plat, fp.tool_pose[:, :2]), atol=1e-9)


@SEEDED
@given(angle=st.floats(-0.9, 0.9), c=st.floats(0.4, 1.0))
def test_inverse_of_forward_recovers_the_tool_path(angle: float, c: float) -> None:
    mech = PushMechanics(0.8, c)
    poses = _straight(angle, 0.03)
    trace = simulate(BAR, poses, np.array([0.0, R]), R, mech)
    g = FaceGeometry.of(BAR, "top")
    s0 = float(trace.face_s[1] * g.length)
    fp = push_tool_path(BAR, "top", trace.object_xy[1:], R, mech, s0, yaw=np.zeros(poses.shape[0] - 1))
    assert np.max(np.linalg.norm(fp.tool_pose[:, :2] - poses[1:, :2], axis=1)) < 2e-5


def test_model_agrees_with_the_mujoco_platform_on_straight_pushes() -> None:
    """docs/design.md section 10's table: a 100 mm face pushed 45 mm at 50 mm/s, 0-60 degrees off its normal,
    on the MuJoCo platform (tool friction 0.8); the model (mu 0.8, c 0.59) replays the recorded tool
    poses: the puck's direction within 2 degrees and its end within 1 mm."""
    from tooltransfer.tools.sim.execution import Rates
    from tooltransfer.tools.sim.platform import SimPlatform
    from tooltransfer.tools.sim.scenarios import line_push

    sim = SimPlatform(BAR)
    mech = PushMechanics(0.8, 0.59)
    for deg in (0, 10, 20, 30, 40, 50, 60):
        obj = np.array([0.0, 0.16])
        direction = np.pi / 2 + np.radians(deg)
        back = -0.002 * np.array([np.cos(direction), np.sin(direction)])
        push = line_push(sim, obj, "top", direction, 0.045, offset=back, duration=0.045 / 0.05 * 1.875,
                         rates=Rates(object_hz=1000, tool_hz=1000))
        ex = push.execution
        model = simulate(BAR, ex.tool_pose, obj, R, mech)
        normal = np.pi / 2 + 0.5 * (ex.tool_pose[0, 2] + ex.tool_pose[-1, 2])
        phi_sim = np.degrees(np.arctan2(*(ex.object_xy[-1] - obj)[::-1]) - normal)
        phi_model = np.degrees(np.arctan2(*(model.final - obj)[::-1]) - normal)
        assert abs(phi_sim - phi_model) < 2.0, (deg, phi_sim, phi_model)
        assert np.linalg.norm(model.final - ex.object_xy[-1]) < 1e-3, deg
