"""SS figures (like the paper's Figs. 9 and 11) are written for both variants."""

from __future__ import annotations

from tooltransfer.planner.apps.plots.switches import plot_generalized_switches, plot_learned_switches
from tooltransfer.planner.planning.ss import learn_switch_skill
from tooltransfer.planner.planning.ss.cases import fig11_task
from tooltransfer.planner.planning.ss.synthetic import synthetic_switches


def test_figures_are_written(tmp_path) -> None:
    demos = synthetic_switches(3, seed=2)
    skills = [learn_switch_skill(demos, virtual=v) for v in ("arch", "line")]
    a = plot_learned_switches(demos, skills, tmp_path / "fig9.png")
    b = plot_generalized_switches(skills[0], {"fig11b": fig11_task("fig11b")}, tmp_path / "fig11.png")
    assert a.stat().st_size > 10_000 and b.stat().st_size > 10_000
