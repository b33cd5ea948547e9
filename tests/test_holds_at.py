"""Where on each face the contact holds the puck at one position (verdicts/holds_at.py), against a placement
of the tool made here another way: the tool's pose from :func:`tooltransfer.tools.contact.contact_pose` (the face
touching the disc at the sampled contact) at the heading at which the Omni's arm plane passes through the
tool's origin at its offset ``d_t`` (found by root finding, none of the module's closed form), the joints from the
Omni's inverse kinematics (its own joint limits, not the reach sector's intervals) and the outline's clearance from
:func:`~tooltransfer.planner.planning.tool_clearance.tool_obstacle_clearance`."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq
from test_verdicts import ROOT, generated

from tooltransfer.planner.planning.setting import setting_from_task, task_skills
from tooltransfer.planner.planning.tool_clearance import TOOL_MARGIN, tool_obstacle_clearance
from tooltransfer.planner.planning.verdicts.hold_windows import NARROW_HOLD, narrowly_held
from tooltransfer.planner.planning.verdicts.holds_at import HOLD_SAMPLES, face_holds, narrow_hold
from tooltransfer.tools.contact import contact_pose
from tooltransfer.tools.objects import DiscObject
from tooltransfer.tools.omni.dh import D_TOOL
from tooltransfer.tools.omni.ik import inverse_kinematics
from tooltransfer.tools.omni.reach import reach_sector


def _world(batch: str, task_id: str):
    task = generated(batch, task_id)
    return task, setting_from_task(task, task_skills(task, need_ss=False))


def _held_here(setting, face, s: float, p: np.ndarray) -> bool:
    """Whether the Omni holds ``face``'s contact at fraction ``s`` on the puck at ``p`` with the tool outline
    :data:`TOOL_MARGIN` clear of the obstacles (module docstring's placement): the heading found by root finding,
    the joints by :func:`inverse_kinematics` of the tool's origin (its first branch within every joint limit, the
    arm reaching forward, at that heading), the clearance by :func:`tool_obstacle_clearance`."""
    sec = reach_sector(setting.platform)
    obj = DiscObject(radius=setting.radius)

    def origin(yaw: float) -> np.ndarray:
        pose = contact_pose(setting.tool, face.name, p, yaw + face.push_angle, s=s, yaw=yaw, obj=obj).pose
        return np.array([pose.x, pose.y])

    def lateral(yaw: float) -> float:  # the tool origin's offset from the arm plane of waist yaw + pi/2, less d_t
        a = yaw + math.pi / 2
        return float((origin(yaw) - sec.centre) @ np.array([-math.sin(a), math.cos(a)])) - D_TOOL

    toward = math.atan2(*(p - sec.centre)[::-1]) - math.pi / 2
    try:
        yaw = brentq(lateral, toward - 0.6, toward + 0.6, xtol=1e-13)
    except ValueError:
        return False
    ik = inverse_kinematics(setting.platform, origin(yaw))
    if not ik.reachable or ik.heading is None or abs(math.remainder(ik.heading - yaw, 2 * math.pi)) > 1e-6:
        return False
    pose = np.array([[*origin(yaw), yaw]])
    return tool_obstacle_clearance(setting.tool, pose, list(setting.obstacles)).distance >= TOOL_MARGIN


@pytest.mark.parametrize(("batch", "task_id", "where"), [("verdicts_200.yaml", "verd200-00049", "start"),
                                                          ("verdicts_200.yaml", "verd200-00049", "target"),
                                                          ("execution_60.yaml", "exec60-00020", "target")])
def test_the_windows_are_the_contacts_a_placement_made_another_way_holds(batch: str, task_id: str,
                                                                          where: str) -> None:
    """Every sampled contact of every face is held by the independent placement exactly where it lies in one of
    the face's windows: the two unknowns of the verdict benchmark whose start or target is held only near one end
    of a face, and a target where a face whose contact range starts half way along it (``foot_top``) holds."""
    task, setting = _world(batch, task_id)
    p = np.asarray(task.start if where == "start" else task.target, dtype=float)
    holds = face_holds(setting, p)
    assert holds, "no face can push"
    for h in holds:
        face = setting.tool.face(h.face)
        s = np.linspace(face.contact_range[0], face.contact_range[1], HOLD_SAMPLES)
        for k in range(HOLD_SAMPLES):
            inside = any(lo - 1e-12 <= s[k] * face.length <= hi + 1e-12 for lo, hi in h.windows)
            assert _held_here(setting, face, float(s[k]), p) == inside, f"{h.face} at s = {s[k]:.3f}"


def test_a_start_held_only_at_the_tip_of_a_face_is_named_narrow() -> None:
    """verd200-00049 (l_shape beside a square obstacle): at its start only ``foot_end`` holds the puck, on the
    last millimetre of its 12 mm (the tool about 1.3 mm from the obstacle there at most); ``top`` and ``left``
    are out of the Omni's reach and ``foot_top`` overlaps the obstacle wherever its contact is. The clause says
    so; at the target every face holds the puck on a wide window, and no clause is made."""
    task, setting = _world("verdicts_200.yaml", "verd200-00049")
    start = {h.face: h for h in face_holds(setting, np.asarray(task.start, dtype=float))}
    assert start["top"].reached == start["left"].reached == 0 and not start["top"].windows
    assert start["foot_top"].reached == HOLD_SAMPLES and not start["foot_top"].windows
    assert start["foot_top"].clearance == 0.0
    (lo, hi), = start["foot_end"].windows
    assert hi == pytest.approx(0.012) and 0.0005 < hi - lo < NARROW_HOLD
    assert 0.001 < start["foot_end"].clearance < 0.002
    clause = narrow_hold(list(start.values()), "the start")
    assert clause == ("at the start the contact holds the puck only on 1 mm of 'foot_end' (a 12 mm face; the tool at "
                      "most 1.3 mm from an obstacle), narrower than the guided search's narrowest windows (2 mm with "
                      "its default contact span)")
    target = face_holds(setting, np.asarray(task.target, dtype=float))
    assert narrow_hold(target, "the target") == "" and min(h.widest for h in target) >= NARROW_HOLD
    assert start["foot_end"].to_dict()["windows"] == [[lo, hi]]
    assert start["top"].to_dict()["clearance"] is None


def test_a_position_no_face_holds_is_said_so() -> None:
    """Beyond the Omni's reach no face holds the puck: every face reaches none of its contacts, and the clause
    says that no face holds it."""
    _, setting = _world("verdicts_200.yaml", "verd200-00049")
    far = reach_sector(setting.platform).centre + np.array([0.5, 0.5])
    holds = face_holds(setting, far)
    assert holds and all(h.reached == 0 and not h.windows and math.isnan(h.clearance) for h in holds)
    assert narrow_hold(holds, "the target").startswith("at the target no face holds the puck")


def test_the_verdict_benchmark_reads_the_widest_hold_of_an_unknown(monkeypatch) -> None:
    """``bench_verdicts.py``'s rows keep the widest window at the start and at the target of an unknown's
    ``holds`` (-1 where no face holds the puck, None without the evidence, as for a solved plan)."""
    monkeypatch.syspath_prepend(str(ROOT / "benchmarks"))
    import bench_verdicts

    task, setting = _world("verdicts_200.yaml", "verd200-00049")
    far = reach_sector(setting.platform).centre + np.array([0.5, 0.5])
    holds = {"start": [h.to_dict() for h in face_holds(setting, np.asarray(task.start, dtype=float))],
             "target": [h.to_dict() for h in face_holds(setting, far)]}
    row = bench_verdicts._widest_holds({"kind": "search_exhausted", "holds": holds})
    assert 0.0005 < row["hold_start"] < NARROW_HOLD and row["hold_target"] == -1.0
    assert bench_verdicts._widest_holds({"kind": "plan"}) == {"hold_start": None, "hold_target": None}
    assert narrowly_held({"holds": holds}) and not narrowly_held({"kind": "plan"})
    wide = [h.to_dict() for h in face_holds(setting, np.asarray(task.target, dtype=float))]
    assert not narrowly_held({"holds": {"start": wide, "target": wide}})


def test_the_batch_report_counts_the_unknowns_held_only_narrowly(tmp_path) -> None:
    """``batch report`` counts, per tool and variant, the unknown rows whose stored evidence holds the start or the
    target only on windows under :data:`NARROW_HOLD`, and says so after the budget's count."""
    import io
    import json

    from rich.console import Console

    from tooltransfer.planner.apps.batch.report import print_report, summarize
    from tooltransfer.planner.apps.batch.store import ResultStore

    task, setting = _world("verdicts_200.yaml", "verd200-00049")
    narrow = [h.to_dict() for h in face_holds(setting, np.asarray(task.start, dtype=float))]
    wide = [h.to_dict() for h in face_holds(setting, np.asarray(task.target, dtype=float))]
    evidence = [{"verdict": "unknown", "budget_limited": False, "holds": {"start": narrow, "target": wide}},
                {"verdict": "unknown", "budget_limited": True, "holds": {"start": wide, "target": wide}},
                {"verdict": "unknown", "budget_limited": True}]  # stored before the evidence had holds
    with ResultStore(tmp_path / "r.sqlite") as store:
        store.add_tasks([{"task_id": f"t{i}", "idx": i, "tool": "l_shape", "n_obstacles": 1} for i in range(3)])
        for i, ev in enumerate(evidence):
            store.put({"task_id": f"t{i}", "variant": "qp/opt", "tool": "l_shape", "status": "unknown",
                       "metrics_json": json.dumps({"evidence": ev})})
        rows = store.rows()
    stats = summarize(rows)
    s = {(g.tool, g.variant): g for g in stats}[("l_shape", "qp/opt")]
    assert (s.unknown, s.unknown_on_budget, s.unknown_narrow) == (3, 2, 1)
    out = io.StringIO()
    print_report(stats, [], Console(file=out, width=400))
    assert "1 held at the start or the target only on contact windows under 2 mm" in out.getvalue()
