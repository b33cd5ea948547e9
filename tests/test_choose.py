"""The ranked choice of a tool (``tooltransfer choose``, ``tt.choose_tool``): the ranking's rules, the
command's JSON and best plan, bad input (exit 2), a ``tools: choose`` batch, and the deadline of the
candidates still planning once a plan passed every execution (``--wait-all`` waits for them)."""

from __future__ import annotations

import json
import math
import time
from pathlib import Path
from types import SimpleNamespace

import pytest
import yaml

from tooltransfer.planner.apps.choose.ranking import (
    Executions,
    known_best,
    margin_score,
    needs_execution,
    plan_order,
    rank_key,
)
from tooltransfer.planner.apps.cli import main

ROOT = Path(__file__).resolve().parents[1]
LIBRARY = ROOT / "tools" / "library"
GOOD = Executions(open_loop=0.001, closed_loop=0.0005, mismatch_closed_loop=0.001)
WIDE = {"friction_cone_margin_min": 0.3, "contact_edge_margin_min": 0.004, "duration": 20.0}


def test_executed_success_ranks_before_margins_and_margins_before_duration() -> None:
    narrow = {**WIDE, "contact_edge_margin_min": 0.0002}
    closed_miss = Executions(open_loop=0.001, closed_loop=0.0025, mismatch_closed_loop=0.001)
    mismatch_miss = Executions(open_loop=0.001, closed_loop=0.001, mismatch_closed_loop=0.004)
    # a plan that passes every execution beats one with wider margins that misses the closed loop by 0.5 mm
    assert rank_key("solved", narrow, GOOD) > rank_key("solved", WIDE, closed_miss)
    # the nominal closed loop weighs more than the mismatched plant's
    assert rank_key("solved", narrow, mismatch_miss) > rank_key("solved", WIDE, closed_miss)
    # equal executions: the wider margins, then the shorter plan
    assert rank_key("solved", WIDE, GOOD) > rank_key("solved", narrow, GOOD)
    assert rank_key("solved", WIDE, GOOD) > rank_key("solved", {**WIDE, "duration": 25.0}, GOOD)
    # any solved plan (even one not executed) before an unknown task, an unknown before a certified infeasible one
    assert rank_key("solved", narrow, None) > rank_key("unknown", {}, None) > rank_key("infeasible", {}, None)


def test_the_margin_score_is_the_weakest_margin_on_its_scale() -> None:
    assert margin_score(WIDE) == 1.0  # every margin at least its scale; no obstacle: infinite clearance
    assert margin_score({**WIDE, "contact_edge_margin_min": 0.001}) == 0.5
    assert margin_score({**WIDE, "friction_cone_margin_min": -0.1}) == 0.0
    assert margin_score({**WIDE, "obstacle_clearance_min": 0.005, "tool_obstacle_clearance_min": 0.0015}) == 0.3
    assert margin_score({"friction_cone_margin_min": float("nan")}) == 0.0


def test_execution_stops_once_the_best_is_known() -> None:
    metrics = [("solved", WIDE), ("infeasible", {}), ("solved", {**WIDE, "duration": 30.0}),
               ("solved", {**WIDE, "contact_edge_margin_min": 0.001})]
    order = [i for i in plan_order(metrics) if metrics[i][0] == "solved"]
    assert order == [0, 2, 3]
    assert needs_execution(order, {}) == [0, 2, 3]
    assert needs_execution(order, {0: GOOD}) == []  # the first in margin order passed everything: it is the best
    failed = Executions(open_loop=0.001, closed_loop=0.01, mismatch_closed_loop=0.001)
    assert needs_execution(order, {0: failed}) == [2, 3]
    assert needs_execution(order, {0: failed, 2: GOOD}) == []
    # a plan that passed with one ahead of it not executed yet: only that one may still rank above it
    assert needs_execution(order, {2: GOOD}) == [0]
    assert known_best(order, {2: GOOD}) is None and known_best(order, {0: failed, 2: GOOD}) == 2
    assert known_best(order, {0: failed}) is None and known_best(order, {0: GOOD}) == 0


def test_choose_ranks_every_tool_writes_the_best_plan_and_draws_them(tmp_path: Path, capsys) -> None:
    from tooltransfer import read_plan

    rake = tmp_path / "tools" / "my_slope.yaml"  # a tool file by path (a copy of a library tool, renamed)
    rake.parent.mkdir()
    data = yaml.safe_load((LIBRARY / "slope.yaml").read_text())
    rake.write_text(yaml.safe_dump({**data, "name": "my_slope"}))
    best = tmp_path / "best.json"
    code = main(["choose", "paper/transfer_tool2", "--tools", f"finger,{rake}", "-o", str(best),
                 "--out", str(tmp_path / "fig"), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["verdict"] == "solved"
    assert set(out) >= {"task", "verdict", "best", "plan", "figure", "wall_time", "cpu_time", "ranking"}
    ranking = out["ranking"]
    assert [e["rank"] for e in ranking] == [1, 2]
    assert {e["tool"] for e in ranking} == {"finger", str(rake)}
    assert {e["name"] for e in ranking} == {"finger", "my_slope"}
    assert all(e["verdict"] in ("solved", "infeasible", "unknown") and e["reason"] for e in ranking)
    first = ranking[0]
    assert out["best"] == first["tool"] and first["executed"]
    assert first["closed_loop_error"] <= 0.002 and first["mismatch_closed_loop_error"] <= 0.003
    assert first["open_loop_error"] <= 0.005 and first["reason"].startswith("passed every execution")
    assert first["friction_cone_margin"] > 0 and first["contact_edge_margin"] > 0 and first["duration"] > 0
    plan = read_plan(best)
    assert plan.status == "solved" and plan.tool["name"] == first["name"] and out["plan"] == str(best)
    assert Path(out["figure"]).is_file() and out["figure"].endswith(".png")
    assert out["cpu_time"] > 0 and out["wall_time"] > 0 and math.isfinite(out["cpu_time"])


@pytest.mark.parametrize("tools, says", [
    ("finger,no_such_tool", "--tools: expected library tool names"),
    ("finger,,slope", "--tools: expected library tool names or tool files, comma-separated, none empty"),
    ("missing/tool.yaml", "no such file"),
    ("{bad}", "a valid tool file"),
])
def test_bad_tools_exit_2_naming_the_option(tools: str, says: str, tmp_path: Path, capsys) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: bad\noutline: [[0, 0], [0.01, 0], [0, 0.01]]\n")  # no a_t
    code = main(["choose", "paper/transfer_tool2", "--tools", tools.replace("{bad}", str(bad))])
    err = capsys.readouterr().err
    assert code == 2 and says in err and "Traceback" not in err


def test_bad_outputs_and_options_exit_2(tmp_path: Path, capsys) -> None:
    assert main(["choose", "paper/transfer_tool2", "--tools", "finger", "-o", str(tmp_path / "no" / "b.json")]) == 2
    assert "-o" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["choose", "paper/transfer_tool2", "--tools", "finger", "--library"])
    assert exc.value.code == 2


def test_a_batch_may_choose_its_tools(tmp_path: Path, small_batch, capsys) -> None:
    from tooltransfer.planner.apps.batch.report import write_report
    from tooltransfer.planner.apps.batch.runner import run_batch
    from tooltransfer.planner.apps.batch.spec import batch_from_dict
    from tooltransfer.planner.apps.batch.store import ResultStore
    from tooltransfer.tools.library import library_names

    every = batch_from_dict({"name": "c", "count": 1, "tools": "choose", "dataset": "."})
    assert every.choose and every.tools == list(library_names())
    listed = batch_from_dict({"name": "c", "count": 1, "tools": list(library_names()), "dataset": "."})
    assert not listed.choose and listed.digest() != every.digest()  # choosing is part of the batch
    batch = small_batch(name="pick", count=1, oe=("qp",), ss=("opt",), tools={"choose": ["trapezoid", "finger"]},
                        obstacles={"count": [0, 0]}, heading=[1.9, 3.1], distance=[0.04, 0.06],
                        timeout=900)
    assert yaml.safe_load(batch.read_text())["tools"] == {"choose": ["trapezoid", "finger"]}
    summary = run_batch(batch, tmp_path / "pick.sqlite", workers=1, progress=False)
    assert summary.stored == 1
    with ResultStore(tmp_path / "pick.sqlite") as store:
        (row,) = store.rows()
    assert row["status"] == "solved", (row["status"], row["reason"], row.get("detail"))
    choice = json.loads(row["metrics_json"])["choice"]
    assert {e["tool"] for e in choice} == {"trapezoid", "finger"}
    assert row["status"] == "solved" and row["tool"] == choice[0]["tool"]
    assert row["closed_loop_error"] == pytest.approx(choice[0]["closed_loop_error"])
    write_report(tmp_path / "pick.sqlite", None)
    assert f"tools chosen (tools: choose): {row['tool']} 1" in capsys.readouterr().out


#: A generated task (the execution benchmark's task 9: seed 60) the rounded pusher solves at once (0.8 s of
#: CPU) and the l_shape certifies infeasible only after a long search (about 80 s of CPU: its faces lean
#: the puck both ways round the Omni's axis, so no polar invariant narrows the backward set).
LONG_FOR_L_SHAPE = {
    "format": "tooltransfer.task/1", "tool": "l_shape", "name": "exec60-00009",
    "skills": {"dataset": str(ROOT / "problems" / "data" / "finger_demos")},
    "start": [-0.10081, 0.078381], "target": [-0.121324, 0.136292],
    "obstacles": [{"kind": "disc", "centre": [-0.12594, 0.102135], "radius": 0.00485}]}

#: A generated task (bench_choose's task 5: seed 2812, six tools) the trapezoid solves at once and the
#: finger certifies infeasible after its search and a backward set (about 6 s of CPU; 25 s before the
#: polar invariant narrowed the set).
LONG_FOR_FINGER = {
    "format": "tooltransfer.task/1", "tool": "trapezoid", "name": "choose100-00005",
    "skills": {"dataset": str(ROOT / "problems" / "data" / "finger_demos")},
    "start": [0.012985, 0.187288], "target": [-0.046971, 0.195274],
    "obstacles": [{"kind": "disc", "centre": [-0.017634, 0.175164], "radius": 0.004442}]}


@pytest.mark.serial
def test_candidates_still_planning_are_stopped_once_a_plan_passed_every_execution(tmp_path: Path, capsys,
                                                                                  monkeypatch) -> None:
    task = tmp_path / "long_for_l_shape.yaml"
    task.write_text(yaml.safe_dump(LONG_FOR_L_SHAPE))
    ended = _pools_ended(monkeypatch)
    code = main(["choose", str(task), "--tools", "rounded_pusher,l_shape", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["best"] == "rounded_pusher"
    best, slow = out["ranking"]
    assert best["reason"].startswith("passed every execution") and not best["stopped"]
    assert best["closed_loop_error"] <= 0.002
    assert slow["tool"] == "l_shape" and slow["stopped"] and not slow["executed"]
    assert slow["verdict"] == "unknown"  # never infeasible (nothing was certified) nor solved
    assert slow["reason"] == "stopped after rounded_pusher passed every execution; `--wait-all` waits for its verdict"
    _check_ended(ended)


@pytest.mark.serial
def test_wait_all_waits_for_every_verdict(monkeypatch) -> None:
    from tooltransfer import choose_tool
    from tooltransfer.problems.task import task_from_dict

    ended = _pools_ended(monkeypatch)
    choice = choose_tool(task_from_dict(LONG_FOR_FINGER, str(ROOT / "long_for_finger.yaml")), ["trapezoid", "finger"],
                         wait_all=True)
    best, finger = choice.ranking
    assert choice.best is best and best.label == "trapezoid" and best.executions is not None
    assert finger.label == "finger" and not finger.stopped
    assert finger.verdict == "infeasible" and finger.reason.startswith("certified infeasible"), finger.reason
    assert choice.cpu >= finger.planning_cpu > 2.0  # the certificate ran to its end, and is counted
    _check_ended(ended)


def _pools_ended(monkeypatch) -> list:
    """The processes of every pool the choice ends (:func:`schedule.stop`), recorded as it ends them."""
    from tooltransfer.planner.apps.choose import schedule

    seen: list = []
    real = schedule.stop

    def recording_stop(*pools) -> None:
        seen.append([list((getattr(p, "_processes", None) or {}).values()) for p in pools])
        real(*pools)

    monkeypatch.setattr(schedule, "stop", recording_stop)
    return seen


def _check_ended(ended: list) -> None:
    """Both of the choice's pools were ended, and every process of theirs was ended and waited for (its
    exit code known, no longer this process's child). Compared by process, not with every child of the
    test process: an earlier test's pool may still be starting or ending one of its own."""
    import multiprocessing

    assert len(ended) == 1 and len(ended[0]) == 2 and ended[0][0], ended  # the planners' pool and the executions'
    procs = [p for pool in ended[0] for p in pool]
    alive = {p.pid for p in multiprocessing.active_children()}
    assert all(p.exitcode is not None and p.pid not in alive for p in procs), \
        [(p.pid, p.name, p.exitcode) for p in procs]


def test_nothing_is_stopped_without_a_plan_that_passed_every_execution() -> None:
    from tooltransfer.planner.apps.choose.executions import Planned
    from tooltransfer.planner.apps.choose.schedule import Options, Work, grace, processes, run_processes, stopped_reason

    assert grace(0.2) == 1.0 and grace(3.5) == 3.5
    assert processes(2, 6) == 6 and processes(2, 10) == 10 and processes(2, 12) == 10 and processes(2, 1) == 2
    assert run_processes(2) == 3 and run_processes(4) == 4  # a plan's three executions at once
    assert "`--wait-all`" in stopped_reason("slope")
    said: list[str] = []
    w = Work(["a", "b", "c"], Options())
    w.add_plan(0, Planned(None, "unknown", "no plan", 1.0, 1.0))
    w.set_deadline(True, said.append)
    assert w.deadline is None and not said  # no plan passed: every verdict is waited for
    waiting = Work(["a", "b"], Options(wait_all=True))
    waiting.set_deadline(True, said.append)
    assert waiting.deadline is None


def _nap(seconds: float) -> float:
    time.sleep(seconds)
    return seconds


def test_a_stopped_pool_has_every_process_ended_and_waited_for() -> None:
    """``schedule.stop`` on a pool whose jobs still run: every process's exit is known when it returns. The
    pool's own thread reaps processes too; before stop joined it, a process it had reaped looked
    running (exit code None) to this thread, 2 times in 60 stops with both cores busy."""
    from tooltransfer.planner.apps.choose import schedule

    for _ in range(30):
        p = schedule.pool(4)
        for _ in range(4):
            p.submit(_nap, 3.0)
        time.sleep(0.02)
        procs = list(p._processes.values())
        schedule.stop(p)
        assert procs and all(q.exitcode is not None for q in procs), [(q.pid, q.exitcode) for q in procs]


def test_a_solved_plan_is_executed_beside_the_candidates_still_planning_once_their_grace_is_over() -> None:
    """A choice's own pools: the executions have their own slots beside the planners', opened by the grace
    after the first solved plan or by the last verdict. Before the fix the planning jobs in flight were
    counted as executions (a tuple compared with ``"plan"``), so that no execution started while two or
    more candidates were still planning (measured on ``choose100-00003``: the best plan, solved at
    1.4 s, executed from 5.1 s, once the fifth candidate had its verdict)."""
    from concurrent.futures import Future

    from tooltransfer.planner.apps.choose.executions import Planned
    from tooltransfer.planner.apps.choose.schedule import Options, Pools, Work, _next_jobs

    pools = Pools(plan=None, run=None, plan_slots=6, run_slots=2, own=True)  # type: ignore[arg-type]
    w = Work([f"tool{i}" for i in range(6)], Options())
    plan = SimpleNamespace(metrics={"duration": 3.0})  # the schedule reads a solved plan's metrics only
    w.add_plan(5, Planned(plan, "solved", "", 1.4, 0.6))  # type: ignore[arg-type]
    inflight: dict[Future, tuple[int, str]] = {Future(): (i, "plan") for i in range(5)}
    start = w.executions_from()
    assert start is not None and start - time.perf_counter() > 1.3  # the grace: max(1 s, 1.4 s)
    assert not w.executions_open() and _next_jobs(w, pools, [], inflight) == []
    w.first_solved_at = time.perf_counter() - 1.5  # the grace over
    assert _next_jobs(w, pools, [], inflight) == [(5, "closed_loop"), (5, "mismatch_closed_loop")]  # both slots
    inflight[Future()] = (5, "closed_loop")
    assert _next_jobs(w, pools, [], inflight) == [(5, "mismatch_closed_loop")]
    given = Pools(plan=None, run=None, plan_slots=2, run_slots=2, own=False)  # type: ignore[arg-type]
    assert _next_jobs(w, given, [], {Future(): (0, "plan")}) == [(5, "closed_loop")]  # one pool: 2 jobs in all
    every = Work(["a", "b"], Options())
    every.add_plan(0, Planned(plan, "solved", "", 30.0, 0.6))  # type: ignore[arg-type]
    every.add_plan(1, Planned(None, "infeasible", "certified", 2.0, 2.0))
    assert every.executions_open()  # every verdict in: no grace to wait for


def test_pools_ended_while_a_worker_sent_its_result_stop_at_once() -> None:
    """A worker ended in the middle of sending its result leaves part of a message in the result pipe (here
    written by this test: a length of 1 MiB, then 16 bytes); the pool's own thread waits for the rest.
    ``stop`` closes this process's write end once every process has ended, so that thread sees the
    pipe's end. Before, ``stop`` waited the 30 s it allows that thread, which then held the interpreter's
    exit (a benchmark's process still waiting 5 min after its last line)."""
    import os
    import struct

    from tooltransfer.planner.apps.choose import schedule

    plan_pool, run_pool = schedule.pool(2), schedule.pool(2)
    for p in (plan_pool, run_pool):
        p.submit(_nap, 5.0)
    time.sleep(0.5)
    manager = plan_pool._executor_manager_thread
    os.write(plan_pool._result_queue._writer.fileno(), struct.pack("!i", 1 << 20) + bytes(16))
    time.sleep(0.3)
    t0 = time.perf_counter()
    schedule.stop(plan_pool, run_pool)
    assert time.perf_counter() - t0 < 15.0
    assert manager is not None and not manager.is_alive()


def test_solve_says_when_its_slower_stages_begin() -> None:
    """``solve(on_slow=...)`` is called once where the condensing found no plan (before the guided search
    and the certificate), never for a plan the condensing found: what a choice's deadline goes by."""
    from tooltransfer.planner.planning.solve import solve
    from tooltransfer.problems.task import load_task

    calls: list[str] = []
    out = solve(load_task(ROOT / "problems" / "hard" / "target_out_of_reach.yaml"), on_slow=lambda: calls.append("x"))
    assert out.verdict == "infeasible" and calls == ["x"]
    quick: list[str] = []
    plan = solve(load_task(ROOT / "problems" / "paper" / "transfer_tool2.yaml"), on_slow=lambda: quick.append("x"))
    assert plan.verdict == "solved" and quick == []


def test_the_deadline_stops_only_candidates_in_their_slower_stages() -> None:
    """With the candidates' stages known: the executions open once fewer candidates are on their quick
    first stage than cores; once a plan passed every execution, the candidates in their slower stages
    (and those never started) are stopped, a candidate still on its quick stage is waited for. Where the
    stages are not known (a pool given, processes spawned) every candidate still planning is stopped."""
    from tooltransfer.planner.apps.choose.executions import Planned
    from tooltransfer.planner.apps.choose.schedule import Options, Work

    plan = SimpleNamespace(metrics={"duration": 3.0})
    w = Work(["a", "b", "c", "d"], Options())
    w.cores, w.slow = 2, [0, 0, 0, 0]
    w.started = {0: 0.0, 1: 0.0, 2: 0.0}  # d not started (more candidates than processes)
    w.add_plan(0, Planned(plan, "solved", "", 0.8, 0.6))  # type: ignore[arg-type]
    assert w.quick() == 3 and not w.executions_open()  # b, c quick, d not started: no core free of them
    w.slow[1] = 1
    assert w.quick() == 2 and not w.executions_open()
    w.slow[2] = 1
    assert w.quick() == 1 and w.executions_open()  # only d left on its quick stage: a core is free
    assert w.due() == []  # no deadline yet
    w.executed[0] = GOOD
    w.set_deadline(True, lambda text: None)
    assert w.deadline is not None and w.due() == [1, 2, 3]  # b, c in their slower stages, d never started
    w.started[3] = 0.0
    assert w.due() == [1, 2]  # d on its quick stage: waited for
    unknown = Work(["a", "b"], Options())
    unknown.add_plan(0, Planned(plan, "solved", "", 0.8, 0.6))  # type: ignore[arg-type]
    unknown.executed[0] = GOOD
    unknown.set_deadline(True, lambda text: None)
    assert unknown.due() == [1]  # stages not known: stopped at once
