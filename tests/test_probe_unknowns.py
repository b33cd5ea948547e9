"""The unknowns' probe (``benchmarks/probe_unknowns.py``): a search under the planner's own rules with the
contact's rolling, to tell an unknown its search left open from one its rules close."""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest
from test_verdicts import ROOT, generated

from tooltransfer.planner.planning.oe.guided_rungs import MIDDLE_SHARE
from tooltransfer.planner.planning.setting import setting_from_task, task_skills
from tooltransfer.planner.planning.solve import qp_options, solve


@pytest.fixture
def probe_module(monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT / "benchmarks"))
    import probe_unknowns

    return probe_unknowns


def _probe(module, batch: str, task_id: str, budget: int = 2000) -> tuple[float, int, bool]:
    task = generated(batch, task_id)
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    options = qp_options(task).model_copy(update={"friction_cone_fraction": MIDDLE_SHARE})
    return module.probe(setting, options, np.array(task.start), np.array(task.target), step=0.003, budget=budget,
                        room=2.5e-4, span=5e-4, windows=0)


def test_the_probe_reaches_a_target_the_planner_reaches(probe_module) -> None:
    """exec60-00001 (no obstacle) is solved; the probe ends on its target (within the goal tolerance) too."""
    task = generated("execution_60.yaml", "exec60-00001")
    assert solve(task).status == "solved"
    d, n, closed = _probe(probe_module, "execution_60.yaml", "exec60-00001")
    assert d <= probe_module.REACHED and n > 0 and not closed


def test_the_probe_closes_its_space_on_an_unknown_whose_way_needs_the_edge_of_a_cone(probe_module) -> None:
    """verd200-00172 (unknown): its only way needs the ``inclined`` face's tool-file cone within 0.15 degrees of
    its edge (benchmarks/README.md); the probe, at the ladder's middle share, closes its space far from it."""
    d, n, closed = _probe(probe_module, "verdicts_200.yaml", "verd200-00172")
    assert closed and d > 0.05 and n < 2000


def test_the_probe_s_windows_cover_every_face_without_gaps(probe_module) -> None:
    """By default the probe's windows tile each face's usable range (the contact range less the contact margin),
    so a step whose contact rolls anywhere on the face has a window to be held by; 25 windows of 0.5 mm left gaps
    on the faces longer than 12.5 mm (``l_shape``'s 40 mm ``left``), where such a step was dropped."""
    from tooltransfer.planner.planning.oe.guided_moves import contact_windows
    from tooltransfer.tools.pushing.inverse import FaceGeometry

    task = generated("verdicts_200.yaml", "verd200-00049")  # the l_shape
    options = qp_options(task).model_copy(update={"contact_span": 5e-4})
    tool = setting_from_task(task, task_skills(task, need_ss=False)).tool
    longest = 0.0
    for face in tool.faces:
        g = FaceGeometry.of(tool, face.name)
        lo, hi = g.lo + options.contact_margin, g.hi - options.contact_margin
        longest = max(longest, hi - lo)
        w = sorted(contact_windows(tool, face.name, options, probe_module.TILED))
        assert w[0][0] == pytest.approx(lo, abs=1e-12) and w[-1][1] == pytest.approx(hi, abs=1e-12)
        assert all(b[0] <= a[1] + 1e-12 for a, b in itertools.pairwise(w)), face.name
        gapped = sorted(contact_windows(tool, face.name, options, 25))
        if hi - lo > 25 * 5e-4:  # what the old default did on a long face
            assert any(b[0] > a[1] + 1e-4 for a, b in itertools.pairwise(gapped)), face.name
    assert longest > 0.03


def test_the_probe_refuses_bad_input(probe_module, tmp_path, capsys) -> None:
    """A results file that cannot be read, or settings out of range: exit code 2 with the reason."""
    assert probe_module.main([str(tmp_path / "none.json")]) == 2
    assert "none.json: not a bench_verdicts.py --json file" in capsys.readouterr().err
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"rows": []}))
    assert probe_module.main([str(bad)]) == 2
    for extra in (["--step", "0"], ["--windows", "4"], ["--room", "-1"], ["--share", "1.5"], ["--directions", "1"]):
        with pytest.raises(SystemExit) as err:
            probe_module.main([str(bad), *extra])
        assert err.value.code == 2


def test_every_step_of_the_funnel_is_a_forward_step_of_the_probe_s_rules(probe_module) -> None:
    """The backward search (``funnel``) from exec60-00001's target: every edge it adds, from a node ``x`` back to
    the node ``q`` it came from, is a step the forward probe takes: some window of the face holds the puck at ``x``
    with the step's direction inside its cone there, the forward probe's own step (``_stepped``) from ``x`` in that
    direction ends on ``q`` (the direction inside the cone at ``q``), and the contact rolls onto a window that holds
    the puck at ``q``. The funnel grows away from the target toward the start."""
    from tooltransfer.planner.planning.oe.guided_moves import _stepped

    task = generated("execution_60.yaml", "exec60-00001")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    options = qp_options(task).model_copy(update={"friction_cone_fraction": MIDDLE_SHARE})
    start, target = np.array(task.start), np.array(task.target)
    edges: list[tuple[np.ndarray, np.ndarray, str, float]] = []
    extent, near, n, closed = probe_module.funnel(setting, options, start, target, step=0.003, budget=40,
                                                  room=2.5e-4, span=5e-4, windows=0, trace=edges)
    assert n == 40 and not closed and extent > 0.01 and near < np.hypot(*(start - target)) - 0.01
    held, free, by_key, _, lands = probe_module._probe_rules(setting, options, 2.5e-4, 5e-4, 0)
    assert len(edges) > 40
    for x, q, face, ang in edges:
        assert free(x) and np.hypot(*(q - x)) == pytest.approx(0.003, abs=1e-12)
        assert abs(math.remainder(float(np.arctan2(*(q - x)[::-1])) - ang, 2 * math.pi)) < 1e-9
        steps = [key for key, mid, half in held(x) if by_key[key].name == face
                 and abs(math.remainder(ang - mid, 2 * math.pi)) <= half
                 and (end := _stepped(by_key[key], x, ang, half, 0.003)) is not None
                 and np.hypot(*(end - q)) < 1e-15 and lands(by_key[key], x, q)]
        assert steps, (x, q, face)
