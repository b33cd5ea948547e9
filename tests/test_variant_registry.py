"""The variant registries (issue 25): one table of OE variants and one of switch variants, every
consumer asks them, and no module outside the registry compares a string with a variant name."""

from __future__ import annotations

import ast
from pathlib import Path
from typing import get_args

import pytest

from tooltransfer.errors import InputError
from tooltransfer.planner.planning import variant_registry as reg
from tooltransfer.problems.task import SSOptions
from tooltransfer.problems.variants import OEVariant, SSVariant

ROOT = Path(__file__).resolve().parents[1]
#: Where variant names may be compared: the package and the benchmarks that consume it.
SCANNED = ("dmp", "planner", "problems", "tools", "benchmarks")
NAMES = frozenset(get_args(OEVariant)) | frozenset(get_args(SSVariant))
#: Comparisons with a variant's spelling that are not a variant choice, with why.
NOT_VARIANTS = {
    "kind != 'arch'",  # the SS skill's virtual object motion, "arch" or "line" (learning/virtual_motion.py)
    "init == 'dmp'",  # the NLP's initial path: the recombined one (planning/ss/opt_variant.py)
    "self.init not in ('auto', 'dmp')",  # the same option's validation
    "which == 'grid'",  # a QP's rows on its time grid or on the dense one (dmp/qp/problem.py)
}
#: The registry module, and modules still to move onto it (none left), by file name.
SKIPPED = {"variant_registry.py"}


def _names_in(node: ast.expr) -> set[str]:
    """The variant names a comparison operand spells: a string, or a tuple, list or set of them."""
    items = node.elts if isinstance(node, ast.Tuple | ast.List | ast.Set) else [node]
    return {i.value for i in items if isinstance(i, ast.Constant) and isinstance(i.value, str)} & NAMES


def _variant_comparisons(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(), str(path))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare) and any(_names_in(o) for o in (node.left, *node.comparators)):
            found.append(ast.unparse(node))
        elif isinstance(node, ast.MatchValue) and _names_in(node.value):
            found.append(f"case {ast.unparse(node.value)}")
    return found


def test_no_string_comparison_with_a_variant_name_outside_the_registry() -> None:
    files = [ROOT / "__init__.py", *(p for d in SCANNED for p in (ROOT / d).rglob("*.py"))]
    bad = []
    for path in files:
        if path.name in SKIPPED:
            continue
        rel = path.relative_to(ROOT).as_posix()
        bad += [f"{rel}: {expr}" for expr in _variant_comparisons(path) if expr not in NOT_VARIANTS]
    assert not bad, "variant choice outside tooltransfer.planner.planning.variant_registry:\n" + "\n".join(bad)


def test_the_scan_sees_each_kind_of_comparison(tmp_path: Path) -> None:
    src = tmp_path / "m.py"
    src.write_text('a == "opt"\nb in ("qp", "x")\n"arch" != c\nd not in ["mapping"]\nmatch e:\n    case "dmp":\n'
                   '        pass\nf == "line"\ng.get("oe", "qp")\n')
    assert _variant_comparisons(src) == ["a == 'opt'", "b in ('qp', 'x')", "'arch' != c", "d not in ['mapping']",
                                         "case 'dmp'"]


def test_the_registries_hold_the_schema_choices() -> None:
    assert set(reg.OE_VARIANTS) == set(get_args(OEVariant))
    assert set(reg.SS_VARIANTS) == set(get_args(SSVariant))
    for name, v in (*reg.OE_VARIANTS.items(), *reg.SS_VARIANTS.items()):
        assert v.name == name


def test_an_unknown_variant_lists_the_registered_ones() -> None:
    with pytest.raises(reg.UnknownVariantError, match="registered: mapping, qp") as oe:
        reg.oe_variant("sqp")
    assert (oe.value.kind, oe.value.name, oe.value.registered) == ("oe", "sqp", ("mapping", "qp"))
    with pytest.raises(reg.UnknownVariantError, match="registered: arch, dmp, grid, opt"):
        reg.switch_planner("spline", None, None, SSOptions())  # type: ignore[arg-type]
    assert isinstance(oe.value, ValueError)


def test_the_one_fallback_rule() -> None:
    """``opt`` falls back to ``arch`` (as ``solve`` always did), then to ``grid``; ``dmp`` reports what
    recombination gives."""
    assert {n: v.fallbacks for n, v in reg.SS_VARIANTS.items()} == {"arch": (), "dmp": (), "grid": (),
                                                                   "opt": ("arch", "grid")}
    assert {n: reg.needs_ss_skill(n) for n in reg.SS_VARIANTS} == {"arch": False, "dmp": True, "grid": False,
                                                                   "opt": True}


def test_a_skill_variant_without_a_skill_is_refused() -> None:
    from tooltransfer.planner.planning.setting import Setting
    from tooltransfer.tools import load_tool
    from tooltransfer.tools.objects import DiscObject
    from tooltransfer.tools.omni.platform import OmniPlatform

    tool = load_tool("slope")
    setting = Setting(tool, OmniPlatform(a_t=tool.a_t), DiscObject(0.0175))
    assert callable(reg.switch_planner("arch", setting, None, SSOptions()))
    for name in ("dmp", "opt"):
        with pytest.raises(InputError, match="an SS skill for the switch variant"):
            reg.switch_planner(name, setting, None, SSOptions())


def test_the_oe_options_come_from_the_task() -> None:
    from tooltransfer.problems.task import OEOptions

    oe = OEOptions(friction_cone_fraction=0.4, contact_margin=0.002, k=0.3)
    for name, v in reg.OE_VARIANTS.items():
        opts = reg.oe_options(name, oe)
        assert isinstance(opts, v.options_type)
        assert (opts.friction_cone_fraction, opts.contact_margin) == (0.4, 0.002)
