"""The world a plan acts in is built once (issue 25): ``solve``, the closed loop and the figures plan
for the same :class:`Setting` of a task, made by :func:`setting_from_task`, and the object's radius
is validated in one place."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from tooltransfer.errors import InputError
from tooltransfer.planner.planning.setting import Setting, setting_from_task, task_skills
from tooltransfer.problems import PAPER_TRANSFER
from tooltransfer.problems.task import load_task
from tooltransfer.tools import load_tool
from tooltransfer.tools.objects import DiscObject
from tooltransfer.tools.omni.platform import OmniPlatform

ROOT = Path(__file__).resolve().parents[1]
#: The task-to-world helpers only :mod:`tooltransfer.planner.planning.setting` calls.
BUILDERS = {"task_tool", "task_platform", "task_obstacles", "effective_margin", "DiscObject"}
#: Modules (by file name) that may call them anyway, with why: the batch generator probes the Omni's
#: reach before a task exists.
ALLOWED = {"generate.py": {"task_tool", "task_platform"}}
#: The setting module, and modules still to move onto :func:`setting_from_task` (none left), by file name.
SKIPPED = {"setting.py"}


def _world(setting: Setting) -> dict:
    return {**setting.describe(), "mechanics": (setting.mechanics.mu, setting.mechanics.c, setting.mechanics.source),
            "margin": setting.margin}


def test_solve_and_the_figures_plan_for_the_task_setting() -> None:
    from tooltransfer.planner.apps.plots.paper_figures import figure_setting
    from tooltransfer.planner.planning.solve import solve

    task = load_task(PAPER_TRANSFER)
    setting = setting_from_task(task, task_skills(task))
    assert setting_from_task(task) == setting  # the mechanics without the SS skill: the same
    _, _, figures = figure_setting(PAPER_TRANSFER)
    assert figures == setting
    assert _world(figures) == _world(setting)
    plan = solve(task)
    described = setting.describe()
    for key in ("platform", "tool", "obstacles"):
        assert getattr(plan, key) == described[key], key
    assert plan.object["radius"] == setting.radius
    m = plan.metrics
    assert (m["mechanics_mu"], m["mechanics_c"], m["safety_margin_used"]) == (
        setting.mechanics.mu, setting.mechanics.c, setting.margin)


def test_the_radius_is_validated_once_by_the_object() -> None:
    tool = load_tool("slope")
    plat = OmniPlatform(a_t=tool.a_t)
    for bad in (0.0, -0.01, float("nan")):
        with pytest.raises(InputError, match="radius"):
            Setting(tool, plat, DiscObject(bad))
    with pytest.raises(InputError, match="a DiscObject"):
        Setting(tool, plat, 0.0175)  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"setting\.margin"):
        Setting(tool, plat, DiscObject(0.0175), margin=-1e-3)
    assert Setting(tool, plat, DiscObject(0.024)).radius == 0.024
    assert Setting(tool, plat, DiscObject(0.024)) == Setting(tool, OmniPlatform(a_t=tool.a_t), DiscObject(0.024))
    assert Setting(tool, plat, DiscObject(0.024)) != Setting(tool, plat, DiscObject(0.024), margin=0.001)


def _calls(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Call):
            f = node.func
            names.add(f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else "")
    return names


def test_only_the_setting_module_builds_the_world_from_a_task() -> None:
    bad = []
    for path in (ROOT / "planner").rglob("*.py"):
        if path.name in SKIPPED:
            continue
        extra = (_calls(path) & BUILDERS) - ALLOWED.get(path.name, set())
        if extra:
            bad.append(f"{path.relative_to(ROOT).as_posix()}: {sorted(extra)}")
    assert not bad, "the world built outside tooltransfer.planner.planning.setting:\n" + "\n".join(bad)
