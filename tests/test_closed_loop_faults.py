"""The closed loop on plants that misbehave (issue 27): every command inside the safety envelope on
every code path, the sensor and arm faults detected and named, the recoverable ones still reaching
the target, and no exception leaving ``execute_closed_loop`` but ``KeyboardInterrupt``, after the
tool was stopped. The plants are the quasi-static push model wrapped in the project's fault plants
(:mod:`tooltransfer.planner.execution.fault_plants`); the paper's transfer task passes its tool a few
millimetres from an obstacle."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely

from tooltransfer.planner.apps.cli import main
from tooltransfer.planner.execution.closed_loop import execute_closed_loop
from tooltransfer.planner.execution.envelope import ENVELOPE_MARGIN, SafetyEnvelope, densify
from tooltransfer.planner.execution.fault_plants import (
    RECOVERABLE,
    DriverFault,
    FrozenCamera,
    TrackingOffset,
    fault_plant,
)
from tooltransfer.planner.execution.guarded_plant import GuardedPlant
from tooltransfer.planner.execution.health import PENETRATION, penetration, take_look
from tooltransfer.planner.execution.loop_stop import LoopStop, UnsafeCommand
from tooltransfer.planner.execution.plant import ModelPlant
from tooltransfer.planner.planning.plan import Plan, read_plan
from tooltransfer.planner.planning.setting import Setting, setting_from_task, task_skills
from tooltransfer.problems.task import task_from_dict
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.ik import joint_path
from tooltransfer.tools.pushing.mechanics import PushMechanics

TRANSFER = Path(__file__).resolve().parents[1] / "problems" / "paper" / "transfer_tool2.yaml"


@pytest.fixture(scope="module")
def plan(tmp_path_factory: pytest.TempPathFactory) -> Plan:
    out = tmp_path_factory.mktemp("faults") / "plan.json"
    assert main(["solve", str(TRANSFER), "-o", str(out), "--json"]) == 0
    return read_plan(out)


@pytest.fixture(scope="module")
def setting(plan: Plan) -> Setting:
    task = task_from_dict(plan.task)
    return setting_from_task(task, task_skills(task))


class Recorder:
    """A plant that passes everything on to ``plant`` and keeps every command it receives, with the
    tool pose it started from (what reached the arm's driver)."""

    def __init__(self, plant: ModelPlant) -> None:
        self.plant = plant
        self.received: list[np.ndarray] = []

    def observe_object(self) -> np.ndarray:
        return self.plant.observe_object()

    def tool_pose(self) -> np.ndarray:
        return self.plant.tool_pose()

    def move_tool(self, t: np.ndarray, tool_pose: np.ndarray) -> None:
        self.received.append(np.vstack([self.plant.tool_pose(), tool_pose]))
        self.plant.move_tool(t, tool_pose)

    def true_object(self) -> np.ndarray:
        return self.plant.true_object()

    def displace_object(self, d: np.ndarray) -> None:
        self.plant.displace_object(d)


def _model(plan: Plan, setting: Setting, c: float = 1.0, seed: int = 0) -> Recorder:
    m = setting.mechanics
    return Recorder(ModelPlant(setting.tool, setting.radius, PushMechanics(m.mu, c * m.c), plan.object["start"],
                               plan.tool_pose[0], platform=setting.platform, camera_noise=0.0015, seed=seed))


def _outline_gap(setting: Setting, path: np.ndarray) -> float:
    """Least distance [m] between the tool outline and the obstacles along ``path`` (K, 3), sampled
    every 0.2 mm with the Omni's heading, computed here with shapely alone."""
    xy = densify(path[:, :2], 2e-4)
    heading = joint_path(setting.platform, xy).heading
    assert np.all(np.isfinite(heading)), "a command left the Omni's reach"
    ring = np.asarray(setting.tool.outline.exterior.coords)
    gap = np.inf
    for (x, y), a in zip(xy, heading, strict=True):
        c, s = np.cos(a), np.sin(a)
        poly = shapely.Polygon(np.array([x, y]) + ring @ np.array([[c, s], [-s, c]]))
        for ob in setting.obstacles:
            shape = ob.polygon() if isinstance(ob, Disc) else ob
            gap = min(gap, float(poly.distance(shape)))
    return gap


def test_the_envelope_refuses_what_it_must_and_sends_nothing(plan: Plan, setting: Setting) -> None:
    env = SafetyEnvelope.of(setting)
    start = plan.tool_pose[0]
    here = np.vstack([start, start])
    assert env.violation(start, here) is None
    ob = setting.obstacles[0]
    through = np.array([[*ob.centre, 0.0]])
    assert "obstacles[0]" in env.violation(start, through)
    assert "reach" in env.violation(start, np.array([[0.5, 0.5, 0.0]]))
    assert "non-finite" in env.violation(start, np.array([[np.nan, 0.1, 0.0]]))
    small = SafetyEnvelope(setting.tool, setting.platform, table=(-1.0, 1.0, -1.0, float(start[1]) - 0.05))
    assert "table" in small.violation(None, np.vstack([start, start]))
    rec = _model(plan, setting)
    guarded = GuardedPlant(rec, env)
    with pytest.raises(UnsafeCommand, match="obstacles"):
        guarded.move_tool(np.array([0.0, 1.0]), np.vstack([start, through[0]]))
    assert not rec.received and guarded.refused


def test_no_command_leaves_the_envelope_on_any_code_path(plan: Plan, setting: Setting) -> None:
    """Runs that take every path of the loop (re-plans and adaptation on a mismatched plant,
    corrections, staged pushes, a steady tracking offset commanded against, a bump, the back-off
    after a frozen camera): every command the arm's driver received keeps the tool outline the
    envelope's margin from the obstacle along its whole straight pieces, within the Omni's reach."""
    runs = [(_model(plan, setting, c=0.6, seed=1), None), (_model(plan, setting, c=1.4, seed=3), None),
            (_model(plan, setting, seed=2), "tracking offset 3 mm"), (_model(plan, setting, seed=0), "bump away"),
            (_model(plan, setting, seed=0), "bump toward obstacle"), (_model(plan, setting, seed=0), "frozen camera")]
    logs, statuses = [], []
    for rec, fault in runs:
        plant = rec if fault is None else fault_plant(fault, rec, obstacles=setting.obstacles, radius=setting.radius,
                                                       margin=setting.margin, target=plan.object["goal"])
        rep = execute_closed_loop(plan, plant)
        logs.append(" ".join(rep.log))
        statuses.append(rep.status)
        assert rec.received
        for path in rec.received:
            if fault == "tracking offset 3 mm":  # the arm's driver got the command the tool tracks 3 mm off
                path = path.copy()
                path[:, :2] -= np.array([0.003, 0.0])
            assert _outline_gap(setting, path) >= ENVELOPE_MARGIN - 1e-6
    text = " ".join(logs)
    assert "staged" in text and "adapted" in text and "backed off" in text
    assert "displaced" in text or "disturbed" in statuses
    assert statuses[-1] == "sensor_fault"


def test_a_wider_envelope_refuses_commands_and_none_reaches_the_arm(plan: Plan, setting: Setting) -> None:
    """The tool passes about 5 mm from the obstacle on this plan: with a 5.5 mm envelope the loop
    meets commands it may not send; it corrects from where the puck is instead or ends ``unsafe``,
    and nothing closer than 5.5 mm reached the arm's driver."""
    rec = _model(plan, setting, seed=1)
    rep = execute_closed_loop(plan, rec, envelope_margin=0.0055)
    assert rep.status == "unsafe" or "instead" in " ".join(rep.log), (rep.status, rep.log)
    assert rep.status in ("reached", "closest", "rounds", "failed", "unsafe")
    assert all(_outline_gap(setting, path) >= 0.0055 - 1e-6 for path in rec.received)


def test_a_frozen_camera_is_detected_within_2_s_and_the_tool_backs_off(plan: Plan, setting: Setting) -> None:
    for after in (1, 3, 8):
        rec = _model(plan, setting)
        frozen = FrozenCamera(rec, after_moves=after)
        rep = execute_closed_loop(plan, frozen)
        assert rep.status == "sensor_fault", rep.reason
        assert frozen.fault_time is not None and frozen.plant_time - frozen.fault_time <= 2.0
        assert penetration(setting.tool, rec.tool_pose(), rec.true_object(), setting.radius) < 0.0
        assert "backed off" in " ".join(rep.log)


@pytest.mark.parametrize("fault", RECOVERABLE)
def test_recoverable_faults_still_reach_the_target(plan: Plan, setting: Setting, fault: str) -> None:
    for seed in (0, 1):
        rec = _model(plan, setting, seed=seed)
        rep = execute_closed_loop(plan, fault_plant(fault, rec, seed=seed, obstacles=setting.obstacles,
                                                    radius=setting.radius, margin=setting.margin,
                                                    target=plan.object["goal"]))
        assert rep.final_error <= 0.003, (fault, seed, rep.status, rep.reason)


def test_a_tool_that_does_not_follow_ends_with_a_tracking_fault(plan: Plan, setting: Setting) -> None:
    rec = _model(plan, setting)
    rep = execute_closed_loop(plan, TrackingOffset(rec, offset=(0.0, 0.008)))
    assert rep.status == "tracking_fault" and "8.0 mm" in rep.reason


@pytest.mark.parametrize(("method", "kwargs", "status", "words"), [
    ("observe_object", {"error": RuntimeError("camera gone"), "times": 10**9}, "failed", "camera gone"),
    ("observe_object", {"value": np.zeros(3), "times": 10**9}, "sensor_fault", "observe_object returned"),
    ("observe_object", {"value": "frame", "times": 10**9, "at": 30}, "sensor_fault", "'frame'"),
    ("tool_pose", {"value": np.array([np.nan, 0.0, 0.0]), "times": 10**9, "at": 4}, "sensor_fault", "nan"),
    ("tool_pose", {"error": ValueError("encoder"), "times": 10**9, "at": 4}, "failed", "tool_pose raised ValueError"),
    ("move_tool", {"error": TimeoutError("late"), "at": 2}, "failed", "move_tool raised TimeoutError: late"),
    ("move_tool", {"error": SystemExit(3), "at": 2}, "failed", "move_tool raised SystemExit: 3"),
])
def test_no_exception_escapes_and_the_reason_names_the_method(plan: Plan, setting: Setting, method: str,
                                                              kwargs: dict, status: str, words: str) -> None:
    rep = execute_closed_loop(plan, DriverFault(_model(plan, setting), method=method, **kwargs))
    assert rep.status == status and words in rep.reason, rep.reason
    assert np.isfinite(rep.final_error)


def test_one_bad_reading_is_taken_again(plan: Plan, setting: Setting) -> None:
    for method in ("observe_object", "tool_pose"):
        rep = execute_closed_loop(plan, DriverFault(_model(plan, setting), method=method, at=6,
                                                    error=RuntimeError("glitch")))
        assert rep.status == "reached" and rep.final_error <= 0.003, (method, rep.reason)


def test_a_keyboard_interrupt_stops_the_tool_first(plan: Plan, setting: Setting) -> None:
    class Stoppable(Recorder):
        stopped = 0

        def stop(self) -> None:
            self.stopped += 1

    rec = _model(plan, setting)
    with pytest.raises(KeyboardInterrupt):
        execute_closed_loop(plan, DriverFault(rec, method="move_tool", at=3, error=KeyboardInterrupt()))
    hold = rec.received[-1]  # no stop(): a command to stay where the tool is
    assert np.allclose(hold[1:, :2], hold[0, :2])
    stoppable = Stoppable(_model(plan, setting).plant)
    with pytest.raises(KeyboardInterrupt):
        execute_closed_loop(plan, DriverFault(stoppable, method="observe_object", at=12, error=KeyboardInterrupt()))
    assert stoppable.stopped == 1


def test_a_plant_that_raises_in_every_method_still_gets_a_report(plan: Plan) -> None:
    class Broken:
        def observe_object(self) -> np.ndarray:
            raise OSError("no camera")

        def tool_pose(self) -> np.ndarray:
            raise OSError("no encoders")

        def move_tool(self, t: np.ndarray, tool_pose: np.ndarray) -> None:
            raise OSError("no arm")

        def true_object(self) -> np.ndarray:
            raise OSError("no truth")

    rep = execute_closed_loop(plan, Broken())
    assert rep.status == "failed" and "plant.tool_pose raised OSError: no encoders" in rep.reason
    assert np.isnan(rep.final_error) and rep.n_pushes == 0


def test_a_look_drops_outliers_and_unusable_frames() -> None:
    rng = np.random.default_rng(0)
    frames = iter([np.array([0.1, 0.2]) + rng.normal(0, 0.0015, 2) for _ in range(9)]
                  + [np.array([0.15, 0.2])])

    def frame() -> np.ndarray:
        return next(frames)

    look = take_look(frame, 10, 0.0015)
    assert look.outliers == 1 and np.hypot(*(look.mean - [0.1, 0.2])) < 0.002
    calls = iter(range(100))

    def flaky() -> np.ndarray:
        if next(calls) % 2:
            raise LoopStop("dropped", status="sensor_fault")
        return np.array([0.1, 0.2])

    assert take_look(flaky, 5, 0.0015).dropped == 4
    with pytest.raises(LoopStop, match="unusable camera frames"):
        take_look(lambda: (_ for _ in ()).throw(LoopStop("never")), 5, 0.0015)
    assert PENETRATION > 0.0


def test_a_back_off_toward_an_obstacle_turns_aside_instead_of_being_refused() -> None:
    """exec60-00036 (trapezoid, one disc, the MuJoCo platform): once the loop has adapted mu and c, a
    re-contact's straight back-off along the face's normal would bring the tool's outline onto the disc.
    The envelope refused it, the correction led to the same back-off, and the run ended ``unsafe``
    23 mm from the target. Turned aside (``LoopRun.back_off``) the tool leaves the object with the
    envelope's margin kept, nothing is refused, and the run ends within 2 mm of the target."""
    pytest.importorskip("mujoco")
    from tooltransfer.planner.apps.batch.generate import generate_tasks
    from tooltransfer.planner.apps.batch.spec import load_batch
    from tooltransfer.planner.planning.solve import solve

    batch = Path(__file__).resolve().parents[1] / "problems" / "batch" / "execution_60.yaml"
    data = next(g.data for g in generate_tasks(load_batch(batch), batch) if g.task_id == "exec60-00036")
    plan = solve(task_from_dict(data, str(batch)))
    assert plan.verdict == "solved"
    rep = execute_closed_loop(plan)
    assert rep.status != "unsafe" and not any("refused" in line for line in rep.log), rep.log
    assert rep.final_error <= 0.002


def test_a_recontact_that_passes_within_the_envelopes_margin_is_not_planned(monkeypatch: pytest.MonkeyPatch) -> None:
    """choose100-00005 of the tool-choice benchmark (l_shape, one obstacle): once the loop has adapted c,
    the re-contact it planned passed 0.18 mm from the obstacle; the envelope refused it and the run
    ended ``unsafe`` 25 mm from the target. Re-contacts keep the envelope's margin now (as a solved plan
    does): the loop plans around it, nothing is refused and the run ends without a safety stop."""
    pytest.importorskip("mujoco")
    monkeypatch.syspath_prepend(str(Path(__file__).resolve().parents[1] / "benchmarks"))
    import bench_choose  # the benchmark's task family, not a copy of it

    from tooltransfer.planner.apps.batch.generate import generate_task
    from tooltransfer.planner.planning.solve import solve
    from tooltransfer.tools.library import library_names

    g = generate_task(bench_choose.batch(100, list(library_names())), 5, str(bench_choose.DATASET))
    plan = solve(task_from_dict({**g.data, "tool": "l_shape"}, str(bench_choose.DATASET / "bench_choose")))
    assert plan.verdict == "solved"
    rep = execute_closed_loop(plan)
    assert rep.status != "unsafe" and not any("refused" in line for line in rep.log), rep.log
    assert rep.final_error < 0.005
