"""Options have one source (issue 17): the planner's options types take their defaults, bounds and
descriptions from the task schema, the CLI its choices, and no option default is written twice."""

from __future__ import annotations

import argparse
import re
from pathlib import Path
from typing import get_args

import pytest

from tooltransfer.planner.apps.cli import build_parser
from tooltransfer.planner.planning.oe.face_frame import CONE_FRACTION
from tooltransfer.planner.planning.oe.mapping_variant import MappingOptions
from tooltransfer.planner.planning.oe.qp_options import TASK_FIELDS, QPOptions
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.planner.planning.solve import mapping_options, qp_options
from tooltransfer.planner.planning.ss.opt_variant import OptOptions
from tooltransfer.problems import variants
from tooltransfer.problems.task import OEOptions, SSOptions, Task, Variants, task_from_dict

ROOT = Path(__file__).resolve().parents[1]
BASE = {"name": "t", "tool": "slope", "start": [0.05, 0.12], "target": [-0.07, 0.18], "skills": {"dataset": "d"}}


MAPPING_FIELDS = ("k", "tube", "friction_cone_fraction", "contact_margin", "contact_span")


@pytest.mark.parametrize(("planner", "names"), [(QPOptions, TASK_FIELDS), (MappingOptions, MAPPING_FIELDS)])
def test_the_planner_options_take_the_schema_fields(planner: type, names: tuple[str, ...]) -> None:
    for name in names:
        mine, schema = planner.model_fields[name], OEOptions.model_fields[name]
        assert (mine.default, mine.metadata, mine.description) == (schema.default, schema.metadata, schema.description)
    assert planner().model_dump(include=set(names)) == OEOptions().model_dump(include=set(names))


def test_the_planner_options_of_a_task_are_its_values() -> None:
    task = task_from_dict({**BASE, "oe": {"n_samples": 77, "candidates": 5, "k": 0.3, "tube": 0.02}})
    qp, mapping = qp_options(task), mapping_options(task)
    assert qp.model_dump(include=set(TASK_FIELDS)) == task.oe.model_dump(include=set(TASK_FIELDS))
    assert qp.screen_samples == QPOptions().screen_samples  # the search's own fields at their defaults
    assert (mapping.k, mapping.tube, mapping.n_samples) == (0.3, 0.02, MappingOptions().n_samples)


def test_the_planner_options_refuse_what_the_schema_refuses() -> None:
    with pytest.raises(ValueError, match="n_samples"):
        QPOptions(n_samples=5)
    with pytest.raises(ValueError, match="k"):
        MappingOptions(k=1.0)


def test_setting_and_switch_defaults_are_the_schema_defaults() -> None:
    from tooltransfer.tools import load_tool
    from tooltransfer.tools.objects import DiscObject
    from tooltransfer.tools.omni.platform import OmniPlatform

    tool, oe = load_tool("slope"), OEOptions()
    setting = Setting(tool, OmniPlatform(a_t=tool.a_t), DiscObject(0.0175))
    assert (setting.margin, CONE_FRACTION) == (Task.model_fields["safety_margin"].default, oe.friction_cone_fraction)
    assert OptOptions().n_knots == SSOptions().n_knots


def _option(parser: argparse.ArgumentParser, command: str, flag: str) -> argparse.Action:
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return next(a for a in sub.choices[command]._actions if flag in a.option_strings)


def test_cli_choices_and_defaults_are_the_schema_ones() -> None:
    parser = build_parser()
    assert tuple(_option(parser, "solve", "--oe").choices) == get_args(Variants.model_fields["oe"].annotation)
    assert tuple(_option(parser, "solve", "--ss").choices) == get_args(Variants.model_fields["ss"].annotation)
    virtual = _option(parser, "learn", "--virtual")
    assert tuple(virtual.choices) == get_args(SSOptions.model_fields["virtual_motion"].annotation)
    assert virtual.default == SSOptions().virtual_motion
    assert _option(parser, "learn", "--k").default == OEOptions().k


def _sources() -> list[Path]:
    return [p for top in ("planner", "problems", "tools", "dmp") for p in (ROOT / top).rglob("*.py")]


def _number(value: float) -> str:
    """A regex for ``value`` as written in Python (0.005, 5e-3, 2e-7, 2e-07, 120, 120.0)."""
    forms = {repr(value), f"{value:g}", f"{value:e}"}
    if float(value).is_integer():
        forms |= {str(int(value)), f"{int(value)}.0"}
    mantissa, _, exp = f"{value:g}".partition("e")
    if exp:
        forms.add(f"{mantissa}e{int(exp)}")
    return "(?:" + "|".join(re.escape(f) for f in sorted(forms)) + r")(?![\d.])"


def test_no_option_default_is_written_twice() -> None:
    """Outside its home (the schema in problems/task.py, the shared defaults in problems/variants.py),
    no field of the task's ``oe`` and ``ss`` sections nor ``safety_margin`` has its default written
    as a default (``name: type = value``, ``name=value``), and neither the margin nor ``k``."""
    homes = {ROOT / "problems" / "task.py", ROOT / "problems" / "variants.py"}
    defaults = {**{n: f.default for n, f in OEOptions.model_fields.items()},
                **{n: f.default for n, f in SSOptions.model_fields.items()},
                "safety_margin": Task.model_fields["safety_margin"].default,
                "margin": variants.SAFETY_MARGIN, "k": variants.MAPPING_K}
    patterns = [re.compile(rf"(?<![\w.]){name}\s*(?::[^=\n]+)?=\s*{_number(value)}") for name, value in defaults.items()
                if isinstance(value, int | float) and not isinstance(value, bool)]
    patterns += [re.compile(r"""["']--k["'].*default\s*=\s*0\.5\b"""),
                 re.compile(rf"""["']safety_margin["']\s*,\s*{_number(variants.SAFETY_MARGIN)}""")]
    found = [f"{p.relative_to(ROOT)}:{i}: {line.strip()}" for p in _sources() if p not in homes
             for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
             if any(pat.search(line) for pat in patterns)]
    assert found == []
    assert variants.SAFETY_MARGIN == Task.model_fields["safety_margin"].default
    assert variants.MAPPING_K == OEOptions.model_fields["k"].default


def test_the_grep_finds_a_copy(tmp_path: Path) -> None:
    """The patterns above catch what they are meant to (a guard against a test that finds nothing)."""
    pat = re.compile(rf"(?<![\w.])k\s*(?::[^=\n]+)?=\s*{_number(0.5)}")
    assert pat.search("def f(k: float = 0.5) -> None:") and pat.search("MappingOptions(k=0.5)")
    assert not pat.search("k: float = MAPPING_K") and not pat.search("self.k = 0.55")
    price = re.compile(rf"(?<![\w.])switch_price\s*(?::[^=\n]+)?=\s*{_number(2e-7)}")
    assert price.search("switch_price: float = 2e-7") and price.search("switch_price=2e-07")
