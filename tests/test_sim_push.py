"""Pushing the puck on the simulated platform with tool 1 (finger).

A straight forward push with the upper face moves the puck forward with the tool, without
penetration, and reports the contact on the upper face. The tool's heading is not free on the
Omni (it follows q1), so the face turns as the tool moves sideways and the round puck, pushed
along the face's normal, rolls along the face and drifts: the platform shows this (measured
figures in the docstrings; ``planner/apps/plots/heading_drift.py`` draws it).
"""

from __future__ import annotations

import numpy as np
import pytest

from tooltransfer.errors import InputError
from tooltransfer.tools import load_tool
from tooltransfer.tools.pose import Pose2D
from tooltransfer.tools.sim import Rates, SimPlatform
from tooltransfer.tools.sim.scenarios import forward_push, sideways_sweep

RATES = Rates(object_hz=1000.0, tool_hz=1000.0)


@pytest.fixture(scope="module")
def sim() -> SimPlatform:
    return SimPlatform(load_tool("finger"))


def test_a_forward_push_moves_the_puck_with_the_tool(sim: SimPlatform) -> None:
    """Tool 1's upper face 10 mm behind the puck, then 70 mm forward: the ideal kinematic push moves
    the puck 60 mm straight forward. Measured: 59.5 mm forward and 4.2 mm to the right, a final
    error of 4.2 mm against that ideal; penetration 0.035 mm. The sideways part is physics, not
    error: the face's heading is -4.2 to -2.6 degrees (it follows q1), so its normal leans right,
    and a round puck is pushed along the normal (the contact force passes through its centre),
    rolling along the face; a frictionless face would drift it 8.6 mm, the 0.8 tool friction
    holds it back. Contact is sensitive to rounding: a 1e-12 m change of the path moves the end by
    0.02 mm, 1e-7 m by 0.08 mm, a path 0.07 - 1e-17 m long instead of 0.07 m by 0.2 mm, hence the
    tolerances."""
    obj = np.array([0.0, 0.15])
    push = forward_push(sim, obj, distance=0.06, gap=0.01, duration=4.0, rates=RATES)
    ex = push.execution
    moved = push.object_motion
    error = np.linalg.norm(ex.object_xy[-1] - (obj + np.array([0.0, 0.06])))
    assert moved[1] == pytest.approx(0.0595, abs=0.0005)
    assert moved[0] == pytest.approx(0.0042, abs=0.0005)  # towards where the face's normal leans
    assert np.all(ex.tool_pose[ex.contact, 2] < 0)  # the normal pi/2 + yaw leans right throughout
    assert error < 0.005  # [m], measured 4.2 mm
    assert ex.max_penetration < 1e-4  # [m], measured 0.035 mm (the bound: about 1 mm)
    assert ex.penetration.max() == pytest.approx(ex.max_penetration)
    # one contact event on the upper face, starting once the 10 mm gap is closed
    assert len(ex.contacts) == 1
    event = ex.contacts[0]
    assert event.face == "upper" and event.piece == 0
    assert 1.0 < event.t_start < 1.3 and event.t_end == pytest.approx(ex.t_tool[-1])
    assert np.array_equal(ex.contact, (ex.t_tool >= event.t_start) & (ex.t_tool <= event.t_end))
    # inside it the puck touches the face in bursts (micrometre separations, see tooltransfer.tools.sim.recorder)
    bursts = np.mean(ex.penetration[ex.contact] > 0)
    assert 0.4 < bursts < 0.9, bursts  # measured 0.71
    assert ex.tracking_error < 1e-3  # [rad]: pushing the 20 g puck hardly loads the arm
    from tooltransfer.tools.sim.mjcf import TCP_BODY, TOOL_BODY

    assert abs(sim.data.body(TCP_BODY).xpos[2]) < 1e-4  # the tool at its height (measured 40 um low)
    assert sim.data.body(TOOL_BODY).xmat[8] > 1.0 - 1e-8  # and level


def test_the_heading_turns_with_the_waist_and_the_puck_drifts_along_the_face(sim: SimPlatform) -> None:
    """The left face 5 mm right of the puck at (40, 160) mm, then an 80 mm sweep to the left.

    Measured: the heading turns by 27.9 degrees (from -27.3 to +0.6; the prototype's "about 30
    degrees over 80 mm"); the left face's normal points left and forward (153 degrees at the
    start), so the puck, pushed along it, travels 40 mm left and 18 mm forward, rolls up the face
    and round the head (so most of the contact is on the head's corners, not on a face), and is
    left behind in front of the tool at t = 3.49 s. Where it leaves
    the head is sensitive: a 1e-12 m change of the path moves its end by 0.4 mm (1e-5 m: 0.8 mm),
    hence the tolerances."""
    obj = np.array([0.04, 0.16])
    push = sideways_sweep(sim, obj, sweep=0.08, gap=0.005, duration=5.0, rates=RATES)
    ex = push.execution
    assert np.degrees(push.heading_change) == pytest.approx(27.9, abs=0.5)
    expect = sim.platform.heading(ex.joints[[0, -1], 0])  # the heading is the one q1 gives
    assert np.allclose(ex.tool_pose[[0, -1], 2], expect, atol=1e-6)
    moved = push.object_motion
    assert moved[0] == pytest.approx(-0.0395, abs=0.0015)
    assert moved[1] == pytest.approx(0.0179, abs=0.0005)  # the drift: pushed left, it goes forward too
    # in the tool frame the puck rolled from the left face to the front of the head
    i0 = np.searchsorted(ex.t_tool, ex.contacts[0].t_start)
    before = Pose2D(*ex.tool_pose[i0]).apply_inverse(ex.object_xy[i0])
    after = Pose2D(*ex.tool_pose[-1]).apply_inverse(ex.object_xy[-1])
    assert before[0] == pytest.approx(-0.0235, abs=5e-4) and before[1] < 0  # beside the left face
    assert after[1] > 0.02  # ahead of the head, no longer pushed
    assert len(ex.contacts) == 1 and ex.contacts[0].t_end == pytest.approx(3.49, abs=0.06)
    assert ex.contacts[0].face is None  # mostly on the head's corners, rolling round
    assert ex.max_penetration < 1e-3


def test_a_wall_stops_the_puck_and_holds_the_arm() -> None:
    """A 60 mm wide wall 22.5 mm ahead of the puck's edge, then a 45 mm stroke: the puck stops at
    the wall and the arm is held, its motors saturated (tracking error 0.096 rad; the operator
    counts a held arm as a failure). Squeezed with the Omni's peak force, the puck goes 0.39 mm
    into the wall and the tool 0.42 mm into the puck; the held arm also lowers the tool 9.7 mm,
    into the table (the model has no tool-table contact, as the issue asks: a limitation for
    squeezes only, a free push keeps it within 0.04 mm of its height)."""
    import shapely

    from tooltransfer.tools import OBJECT_RADIUS

    wall = shapely.Polygon([(-0.03, 0.19), (0.03, 0.19), (0.03, 0.21), (-0.03, 0.21)])
    sim = SimPlatform(load_tool("finger"), obstacles=[wall])
    push = forward_push(sim, (0.0, 0.15), distance=0.04, gap=0.005, duration=3.0)
    ex = push.execution
    clearance = np.array([wall.distance(shapely.Point(p)) for p in ex.object_xy]) - OBJECT_RADIUS
    assert clearance.min() > -5e-4  # [m] the puck hardly goes into the wall (measured 0.39 mm)
    assert clearance.min() < 1e-3 and push.object_motion[1] > 0.015  # it reached the wall
    assert ex.tracking_error > 0.02  # [rad] the arm is held
    assert ex.max_penetration < 1e-3  # measured 0.42 mm
    # squeezed, the tool stays level (the joint equalities hold: 1.2e-4 rad), but the held arm's
    # joint errors lower it 9.7 mm: it passes into the table, which it does not collide with
    from tooltransfer.tools.sim.mjcf import TCP_BODY, TOOL_BODY

    tilt = np.arccos(min(1.0, sim.data.body(TOOL_BODY).xmat.reshape(3, 3)[2, 2]))
    assert tilt < 1e-3
    assert sim.data.body(TCP_BODY).xpos[2] == pytest.approx(-0.0097, abs=0.001)
    with pytest.raises(InputError, match="clear of obstacle0_0"):
        sim.reset([0.0, 0.18], tool_xy=[0.0, 0.12])  # the puck would be inside the wall


def test_a_two_millisecond_step_gives_the_same_push() -> None:
    """The forward push with a 2 ms step ends 0.34 mm from the 1 ms one (the issue: 1-2 ms are ok)."""
    from tooltransfer.tools.sim import SimConfig

    ends = [forward_push(SimPlatform(load_tool("finger"), config=SimConfig(timestep=dt))).execution.object_xy[-1]
            for dt in (0.001, 0.002)]
    assert np.linalg.norm(ends[1] - ends[0]) < 6e-4
