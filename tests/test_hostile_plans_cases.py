"""Hostile plan files (issue 16, class 6): a solved plan edited by hand to lie about itself or its task.
``read_plan`` refuses what does not hold together (status, types, finite values, lengths, order) and
``check_plan`` what does not agree with the task (start and target, joint limits, the joints' forward
kinematics, the tool into the puck or an obstacle, speeds, the push model's replay, the duration);
``tooltransfer simulate`` exits 2 with one line naming the file and the field before running anything,
and ``--force`` runs a plan that fails the checks anyway, with a warning (not one beyond the
simulation's bounds)."""

from __future__ import annotations

import copy
import json
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.cli import main
from tooltransfer.planner.execution.simulate import check_plan
from tooltransfer.planner.learning.segmentation.geometry import table_poses
from tooltransfer.planner.planning.plan import PlanFileError, read_plan

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def plan_doc(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """The transfer task's qp/opt plan as JSON data."""
    from tooltransfer.planner.planning.solve import solve
    from tooltransfer.problems.task import load_task

    path = ROOT / "problems" / "paper" / "transfer_tool2.yaml"
    plan = solve(load_task(path), path)
    assert plan.status == "solved", plan.reason
    out = plan.write(tmp_path_factory.mktemp("plan") / "plan.json")
    return json.loads(out.read_text())


def _fk(d: dict) -> None:
    """Tool poses recomputed from the (edited) joints: a careful liar keeps them consistent."""
    p = d["platform"]
    d["samples"]["tool_pose"] = table_poses(np.array(d["samples"]["joints"]), p["a_t"], p["base_xy"],
                                            p["base_yaw"]).tolist()


def _approach_into_the_puck(d: dict) -> None:
    q = np.array(d["samples"]["joints"])
    k = d["samples"]["phase"].index("push")
    q[:k, 2] -= np.linspace(0.0, 0.25, k)  # the forearm drives the tool 25 mm on
    d["samples"]["joints"] = q.tolist()
    _fk(d)


def _start_on_the_puck(d: dict) -> None:
    from tooltransfer.problems.task import task_from_dict, task_platform, task_tool
    from tooltransfer.tools.omni.ik import inverse_kinematics

    task = task_from_dict(d["task"])
    platform = task_platform(task, task_tool(task))
    q0 = inverse_kinematics(platform, np.array(task.start)).q
    d["samples"]["joints"][0] = q0.tolist()
    _fk(d)


def _sweep_through(d: dict) -> None:
    """The tool path of the pushes moved 15 mm forward (through the puck), joints by inverse kinematics."""
    from tooltransfer.problems.task import task_from_dict, task_platform, task_tool
    from tooltransfer.tools.omni.ik import joint_path

    task = task_from_dict(d["task"])
    platform = task_platform(task, task_tool(task))
    pose = np.array(d["samples"]["tool_pose"])
    push = np.array([ph == "push" for ph in d["samples"]["phase"]])
    pose[push, :2] += [0.0, 0.015]
    q = np.array(d["samples"]["joints"])
    q[push] = joint_path(platform, pose[push, :2]).q
    d["samples"]["joints"] = q.tolist()
    _fk(d)


def _set(path: str, value: object) -> Callable[[dict], None]:
    def edit(d: dict) -> None:
        node = d
        keys = path.split(".")
        for k in keys[:-1]:
            node = node[int(k)] if isinstance(node, list) else node[k]
        last = keys[-1]
        if isinstance(node, list):
            node[int(last)] = value
        else:
            node[last] = value
    return edit


def _times(k: float) -> Callable[[dict], None]:
    return lambda d: d["samples"].update(t=[k * t for t in d["samples"]["t"]])


def _shift(key: str, rows: slice, delta: tuple[float, ...]) -> Callable[[dict], None]:
    def edit(d: dict) -> None:
        a = np.array(d["samples"][key])
        a[rows] += delta
        d["samples"][key] = a.tolist()
    return edit


#: case -> (edit, the field the message names, words; read: refused by read_plan, else by check_plan)
READ_CASES: dict[str, tuple[Callable[[dict], None], str, tuple[str, ...]]] = {
    "joints true/false": (_set("samples.joints.5", [True, False, True]), "samples.joints[5][0]", ("a number",)),
    "a joint as a string": (_set("samples.joints.5.1", "0.3"), "samples.joints[5][1]", ("'0.3'",)),
    "a joint null": (_set("samples.joints.9.2", None), "samples.joints[9][2]", ()),
    "NaN in samples.joints": (_set("samples.joints.12.1", float("nan")), "samples.joints[12][1]", ("finite",)),
    "Infinity in tool_pose": (_set("samples.tool_pose.7.0", float("inf")), "samples.tool_pose[7][0]", ("finite",)),
    "NaN in t": (_set("samples.t.3", float("nan")), "samples.t[3]", ("finite",)),
    "a row of 2 joints": (_set("samples.joints.4", [0.1, 0.2]), "samples.joints[4]", ("3 numbers",)),
    "an unknown status": (_set("status", "great"), "status", ("solved, infeasible, unknown, violated",)),
    "status a number": (_set("status", 1), "status", ()),
    "no status": (lambda d: d.pop("status"), "status", ()),
    "reason a list": (_set("reason", ["a"]), "reason", ()),
    "unequal lengths": (lambda d: d["samples"].update(phase=d["samples"]["phase"][:-3]), "samples.phase",
                        ("entries like samples.t",)),
    "time going back": (lambda d: d["samples"]["t"].__setitem__(10, d["samples"]["t"][8]), "samples.t[10]",
                        ("a time after",)),
    "an unknown phase": (_set("samples.phase.3", "dance"), "samples.phase[3]", ("'dance'",)),
    "a face a number": (_set("samples.face.3", 7), "samples.face[3]", ()),
    "joints missing": (lambda d: d["samples"].pop("joints"), "samples.joints", ()),
    "samples a list": (_set("samples", [1, 2]), "samples", ()),
    "task a list": (_set("task", [1]), "task", ()),
    "a metric true": (_set("metrics.goal_error", True), "metrics.goal_error", ()),
    "a push time a word": (_set("pushes.0.t_start", "soon"), "pushes[0].t_start", ()),
    "a push ending first": (_set("pushes.0.t_end", -1.0), "pushes[0].t_end", ()),
    "faces not names": (_set("switches.0.faces", [1, 2]), "switches[0].faces", ()),
    "another format": (_set("format", "tooltransfer.plan/9"), "format", ()),
    "solved without samples": (lambda d: d["samples"].update({k: [] for k in d["samples"]}), "samples.t",
                               ("at least 2 samples",)),
}
CHECK_CASES: dict[str, tuple[Callable[[dict], None], str, tuple[str, ...]]] = {
    "1000 times faster": (_times(1e-3), "samples.t", ("max_tool_speed", "1e+03 times")),
    "10 times faster": (_times(0.1), "samples.t", ("max_tool_speed",)),
    "stretched 10^4 in time": (_times(1e4), "samples.t", ("at most 1800 s",)),
    "starts late": (lambda d: d["samples"].update(t=[t + 50.0 for t in d["samples"]["t"]]), "samples.t[0]", ()),
    "tool poses edited alone": (_shift("tool_pose", slice(100, 200), (0.0, 0.01, 0.0)), "samples.tool_pose[100]",
                                ("forward kinematics",)),
    "a heading edited": (_shift("tool_pose", slice(40, 41), (0.0, 0.0, 0.3)), "samples.tool_pose[40]",
                         ("forward kinematics",)),
    "joints beyond the limits": (lambda d: (_shift("joints", slice(50, 60), (2.5, 0.0, 0.0))(d), _fk(d)),
                                 "samples.joints[50][0]", ("joint limits",)),
    "the approach drives into the puck": (_approach_into_the_puck, "samples.tool_pose[", ("into the object",)),
    "the start on the puck": (_start_on_the_puck, "samples.tool_pose[0]", ("into the object",)),
    "the pushes sweep through the puck": (_sweep_through, "samples.tool_pose[", ("into the object",)),
    "the object path moved at its start": (_set("samples.object_xy.0", [0.0, 0.15]), "samples.object_xy[0]",
                                           ("the task's start",)),
    "the task's start moved": (lambda d: d["task"].update(start=[d["task"]["start"][0] + 0.01,
                                                                 d["task"]["start"][1]]),
                               "samples.object_xy[0]", ("the task's start",)),
    "the task's target moved": (lambda d: d["task"].update(target=[d["task"]["target"][0],
                                                                   d["task"]["target"][1] + 0.02]),
                                "samples.object_xy[", ("the task's target",)),
    "the object path lies mid-plan": (_shift("object_xy", slice(400, 800), (0.0, 0.003)), "samples.object_xy",
                                      ("push model",)),
    "an unknown tool in the task": (_set("task.tool", "hammer"), "task: tool", ("library tool",)),
    "a task field of the wrong type": (_set("task.start", "here"), "task: start", ()),
    "absurd mechanics": (_set("metrics.mechanics_mu", 100.0), "metrics.mechanics_mu", ()),
    "an obstacle on the tool's way": (lambda d: d["task"].update(obstacles=[
        {"kind": "disc", "centre": d["samples"]["tool_pose"][300][:2], "radius": 0.002}]),
        "samples.tool_pose[", ("obstacles[0]",)),
}


def _write(tmp_path: Path, doc: dict, edit: Callable[[dict], None]) -> Path:
    d = copy.deepcopy(doc)
    edit(d)
    p = tmp_path / "edited.json"
    p.write_text(json.dumps(d))
    return p


def test_the_plan_as_written_passes_its_checks(plan_doc: dict, tmp_path: Path) -> None:
    p = _write(tmp_path, plan_doc, lambda d: None)
    check_plan(read_plan(p), str(p))


@pytest.mark.parametrize("name", sorted(READ_CASES))
def test_read_plan_refuses_naming_the_file_and_the_field(plan_doc: dict, tmp_path: Path, name: str) -> None:
    edit, field, words = READ_CASES[name]
    p = _write(tmp_path, plan_doc, edit)
    with pytest.raises(PlanFileError) as err:
        read_plan(p)
    msg = str(err.value)
    assert msg.startswith(f"{p}: {field}") and "\n" not in msg, msg
    for w in words:
        assert w in msg, msg


@pytest.mark.parametrize("name", sorted(CHECK_CASES))
def test_check_plan_refuses_naming_the_file_and_the_field(plan_doc: dict, tmp_path: Path, name: str) -> None:
    edit, field, words = CHECK_CASES[name]
    p = _write(tmp_path, plan_doc, edit)
    plan = read_plan(p)
    start = time.perf_counter()
    with pytest.raises(InputError) as err:  # PlanFileError, or the task's TaskFileError (both name the file)
        check_plan(plan, str(p))
    assert time.perf_counter() - start < 10
    msg = str(err.value)
    assert msg.startswith(f"{p}: {field}") and "\n" not in msg, msg
    for w in words:
        assert w in msg, msg


@pytest.mark.parametrize("raw, words", [
    ("[" * 100_000 + "]" * 100_000, ("<file>", "nested")),
    (bytes(range(256)) * 20, ("<file>", "UTF-8")),
    ("format: tooltransfer.plan/1\n", ("line 1, column 1", "valid JSON")),
    ("", ("valid JSON",)),
    ("[]", ("format",)),
])
def test_files_that_are_not_plans(tmp_path: Path, raw: str | bytes, words: tuple[str, ...]) -> None:
    p = tmp_path / "plan.json"
    p.write_bytes(raw if isinstance(raw, bytes) else raw.encode())
    with pytest.raises(PlanFileError) as err:
        read_plan(p)
    for w in words:
        assert w in str(err.value), str(err.value)


def test_a_plan_file_too_large_is_refused_before_it_is_read(tmp_path: Path, monkeypatch) -> None:
    import tooltransfer.planner.planning.plan as plan_module

    p = tmp_path / "plan.json"
    p.write_text(" " * 5000 + "{}")
    monkeypatch.setattr(plan_module, "MAX_PLAN_BYTES", 4096)
    with pytest.raises(PlanFileError, match="at most 0 MB"):
        read_plan(p)


@pytest.mark.parametrize("name", ["joints true/false", "an unknown status", "1000 times faster",
                                  "the pushes sweep through the puck", "stretched 10^4 in time"])
def test_simulate_exits_2_with_one_line_before_running(plan_doc: dict, tmp_path: Path, capsys, name: str) -> None:
    edit = {**READ_CASES, **CHECK_CASES}[name][0]
    p = _write(tmp_path, plan_doc, edit)
    start = time.perf_counter()
    assert main(["simulate", str(p)]) == 2
    assert time.perf_counter() - start < 10
    err = capsys.readouterr().err
    assert err.startswith(f"tooltransfer: error: {p}: ") and err.count("\n") == 1 and "Traceback" not in err, err


def test_force_runs_a_plan_that_fails_its_checks_with_a_warning(plan_doc: dict, tmp_path: Path, capsys) -> None:
    p = _write(tmp_path, plan_doc, _times(1e-3))
    assert main(["simulate", str(p), "--force", "--json"]) == 0
    out = capsys.readouterr()
    assert "warning" in out.err and "max_tool_speed" in out.err and "--force" in out.err
    assert "open_loop_final_error" in json.loads(out.out)
    # beyond the simulation's bounds --force does not help
    p = _write(tmp_path, plan_doc, _times(1e4))
    assert main(["simulate", str(p), "--force"]) == 2
    assert "at most 1800 s" in capsys.readouterr().err


def test_a_violated_plan_is_not_run_unless_forced(plan_doc: dict, tmp_path: Path, capsys) -> None:
    p = _write(tmp_path, plan_doc, lambda d: d.update(status="violated", reason="hard checks violated: cone (x)"))
    assert main(["simulate", str(p)]) == 1
    assert "violated" in capsys.readouterr().out
