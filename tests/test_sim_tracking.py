"""PD tracking on the simulated platform: a smooth joint path is tracked closely without contact,
chunks equal one execution, executions are deterministic, recordings come on a shared time grid
at the requested rates, and bad inputs are refused naming the field and sample."""

from __future__ import annotations

import numpy as np
import pytest

from tooltransfer.errors import InputError
from tooltransfer.tools import load_tool
from tooltransfer.tools.omni.ik import tool_pose_world
from tooltransfer.tools.sim import Execution, Rates, SimPlatform

QA, QB = np.array([-0.4, 0.2, 0.8]), np.array([0.5, 0.6, 1.2])


def _min_jerk_joints(dur: float, n: int = 101) -> tuple[np.ndarray, np.ndarray]:
    t = np.linspace(0.0, dur, n)
    s = t / dur
    return t, QA + (10 * s**3 - 15 * s**4 + 6 * s**5)[:, None] * (QB - QA)


def _min_jerk_rates(t: np.ndarray, dur: float) -> np.ndarray:
    s = t / dur
    return (30 * s**2 - 60 * s**3 + 30 * s**4)[:, None] * (QB - QA) / dur


@pytest.fixture(scope="module")
def sim() -> SimPlatform:
    return SimPlatform(load_tool("finger"))


def test_a_smooth_joint_path_is_tracked_without_contact(sim: SimPlatform) -> None:
    """0.9 rad of q1 in 2 s (minimum jerk), puck out of the way: measured 2.9e-4 rad and 0.07 mm."""
    sim.reset([0.15, 0.0], q0=QA)
    t, q = _min_jerk_joints(2.0)
    ex = sim.execute(t, q, rates=Rates(object_hz=100.0, tool_hz=1000.0))
    assert ex.tracking_error < 5e-4  # [rad]
    planned = np.array([tool_pose_world(sim.platform, r)[:2, 3] for r in ex.joints_ref])
    assert np.abs(ex.tool_pose[:, :2] - planned).max() < 1.5e-4  # [m]
    assert np.abs(sim.joints - QB).max() < 1e-4  # where it ends, still settling by 2e-5 rad
    assert not ex.contact.any() and not ex.contacts
    assert np.array_equal(ex.object_xy[-1], [0.15, 0.0]) or np.abs(ex.object_xy[-1] - [0.15, 0.0]).max() < 1e-9


def test_executing_in_chunks_equals_executing_at_once(sim: SimPlatform) -> None:
    """Equal up to the rounding of the chunk's step times (``0.37 + i dt`` against ``(370 + i) dt``)
    when the chunks share the velocity reference (finite differences differ at a cut)."""
    t, q = _min_jerk_joints(1.0)
    qd = _min_jerk_rates(t, 1.0)
    rates = Rates(object_hz=30.0, tool_hz=100.0)
    sim.reset([0.15, 0.0], q0=QA)
    whole = sim.execute(t, q, qd, rates=rates)
    end_whole = sim.observe()
    sim.reset([0.15, 0.0], q0=QA)
    k = 37  # t[37] = 0.37 s: neither grid falls on it
    first = sim.execute(t[: k + 1], q[: k + 1], qd[: k + 1], rates=rates)
    parts = [first, sim.execute(t[k:], q[k:], qd[k:], rates=rates)]
    both = Execution.concat(parts)
    assert sim.time == pytest.approx(1.0)
    for name in ("t_object", "t_tool", "contact"):
        assert np.array_equal(getattr(both, name), getattr(whole, name)), name
    for name in ("object_xy", "tool_pose", "joints"):
        assert np.abs(getattr(both, name) - getattr(whole, name)).max() < 1e-12, name
    assert all(np.abs(a - b).max() < 1e-12 for a, b in zip(sim.observe(), end_whole, strict=True))


def test_the_same_inputs_give_identical_outputs() -> None:
    outs = []
    for _ in range(2):
        s = SimPlatform(load_tool("finger"))
        s.reset([0.15, 0.0], q0=QA)
        outs.append(s.execute(*_min_jerk_joints(0.5)))
    a, b = outs
    assert all(np.array_equal(getattr(a, n), getattr(b, n)) for n in ("object_xy", "tool_pose", "joints"))


def test_recordings_come_at_the_requested_rates_on_the_platform_clock(sim: SimPlatform) -> None:
    sim.reset([0.15, 0.0], q0=QA)
    ex = sim.execute(*_min_jerk_joints(1.0), rates=Rates(object_hz=30.0, tool_hz=250.0))
    assert ex.t_object[0] == 0.0 and ex.t_tool[0] == 0.0 and ex.t_tool[-1] < 1.0
    assert len(ex.t_object) == 30 and len(ex.t_tool) == 250
    assert np.allclose(np.diff(ex.t_tool), 0.004)
    # the camera's samples fall on the first physics step at or after each 1/30 s
    assert np.allclose(ex.t_object, np.ceil(np.arange(30) / 30 * 1000 - 1e-6) / 1000)
    assert ex.object_xy.shape == (30, 2) and ex.tool_pose.shape == ex.joints.shape == (250, 3)
    assert ex.contact.shape == ex.penetration.shape == (250,)


def test_bad_inputs_are_refused_naming_the_field(sim: SimPlatform) -> None:
    sim.reset([0.15, 0.0], q0=QA)
    t, q = _min_jerk_joints(1.0)
    with pytest.raises(InputError) as err:
        sim.execute(t, q[:, :2])
    assert err.value.field == "q"
    beyond = q.copy()
    beyond[60, 2] = 1.7  # q3's upper limit is 1.6 rad
    with pytest.raises(InputError) as err:
        sim.execute(t, beyond)
    assert err.value.field == "q[60]"
    with pytest.raises(InputError) as err:
        sim.execute(t, q + 0.2)  # starts 0.2 rad away from the arm
    assert err.value.field == "q[0]"
    with pytest.raises(InputError) as err:
        sim.execute(t[::-1], q)
    assert err.value.field == "t"
    with pytest.raises(InputError) as err:
        sim.execute(t, q, rates=Rates(object_hz=2000.0))
    assert err.value.field == "rates"
    with pytest.raises(InputError) as err:
        sim.reset([0.15, 0.0])
    assert err.value.field == "q0"
    with pytest.raises(InputError) as err:
        sim.reset([0.15, 0.0], q0=[0.0, 0.0, -0.5])
    assert err.value.field == "q0"


def test_an_unreachable_tool_path_is_refused_naming_the_sample(sim: SimPlatform) -> None:
    sim.reset([0.15, 0.0], tool_xy=[0.0, 0.15])
    t = np.linspace(0.0, 1.0, 11)
    xy = np.column_stack([np.zeros(11), np.linspace(0.15, 0.25, 11)])  # reach ends near 0.217 m
    with pytest.raises(InputError) as err:
        sim.execute_tool_path(t, xy)
    assert err.value.field == "tool_xy[7]" and "0.22" in str(err.value)


def test_a_puck_placed_inside_the_tool_is_refused(sim: SimPlatform) -> None:
    with pytest.raises(InputError, match="clear of tool_piece"):
        sim.reset([0.0, 0.15], tool_xy=[0.0, 0.15])


def _recording(t0: float, n: int, events: tuple) -> Execution:
    t = t0 + 0.001 * np.arange(n)
    z = np.zeros((n, 3))
    return Execution(t, z[:, :2], z[:, 0], t, z, z, z, np.zeros(n, dtype=bool), z[:, 0], events)


def test_concat_joins_a_contact_event_cut_by_a_chunk_boundary() -> None:
    from tooltransfer.tools.sim import ContactEvent

    a = _recording(0.0, 100, (ContactEvent(0.01, 0.02, 0, 1e-5, "left"), ContactEvent(0.09, 0.099, 0, 2e-5, "upper")))
    b = _recording(0.1, 100, (ContactEvent(0.105, 0.15, 1, 3e-5, "upper"),))
    both = Execution.concat([a, b])
    assert both.contacts == (ContactEvent(0.01, 0.02, 0, 1e-5, "left"), ContactEvent(0.09, 0.15, 0, 3e-5, "upper"))
    assert len(both.t_tool) == 200 and both.max_penetration == 3e-5
    with pytest.raises(InputError):
        Execution.concat([b, a])  # out of order
    with pytest.raises(InputError):
        Execution.concat([])
