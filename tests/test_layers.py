"""Arrows point down (issue 17, issue 25): the generic helpers (tooltransfer.errors, .validation, .atomic,
.versioned_json, .readable_json, .timing, .yaml_file) at the bottom, then dmp, tools, problems, planner;
inside planner its sub-packages common < learning < planning < execution < apps, and inside apps the
operator and the figures < batch runs < the command line and the paper's run. No module imports one of a
higher layer or sub-layer (also inside a function), the imports have no circle, every planner module
sits in a sub-package, and no module only re-exports another's names (a shim)."""

from __future__ import annotations

import ast
from graphlib import CycleError, TopologicalSorter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BOTTOM = ("errors", "validation", "atomic", "versioned_json", "readable_json", "timing", "yaml_file")
LAYERS = {**dict.fromkeys(BOTTOM, 0), "dmp": 1, "tools": 2, "problems": 3, "planner": 4}
#: planner's sub-packages, bottom to top: learning sits below planning, which plans with the learned skills
PLANNER = {"common": 0, "learning": 1, "planning": 2, "execution": 3, "apps": 4}
#: inside apps: the scripted operator, the figures and the tool choice, then batch runs (their figures use plots.save;
#: a batch may choose its tools), then the rest
APPS = {"operator": 0, "plots": 0, "choose": 0, "batch": 1}
APPS_TOP = 2


def _modules() -> dict[str, Path]:
    out = {}
    bottom = [ROOT / f"{name}.py" for name in BOTTOM]
    for path in [*bottom, *(p for top in ("dmp", "tools", "problems", "planner") for p in (ROOT / top).rglob("*.py"))]:
        parts = path.relative_to(ROOT).with_suffix("").parts
        out[".".join(("tooltransfer", *(parts[:-1] if parts[-1] == "__init__" else parts)))] = path
    return out


MODULES = _modules()


def _imports(path: Path, module_level_only: bool) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    nodes = tree.body if module_level_only else list(ast.walk(tree))
    found = set()
    for node in nodes:
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
            found |= {f"{node.module}.{a.name}" for a in node.names}  # from package import module
    return {m for m in found if m in MODULES}


def _layer(module: str) -> tuple[int, ...]:
    """(layer, planner sub-package, part of apps), compared on the length both have: modules of one
    sub-package are ordered by the next number only; tooltransfer.planner sits on its sub-packages."""
    parts = module.split(".")
    top = LAYERS[parts[1]]
    if parts[1] != "planner":
        return (top,)
    if len(parts) == 2:
        return (top, len(PLANNER))
    sub = PLANNER[parts[2]]
    if parts[2] != "apps":
        return (top, sub)
    return (top, sub, APPS.get(parts[3], APPS_TOP)) if len(parts) > 3 else (top, sub)


def _runs_up(mod: str, dep: str) -> bool:
    a, b = _layer(mod), _layer(dep)
    n = min(len(a), len(b))
    return b[:n] > a[:n]


def test_no_import_runs_up_the_layers() -> None:
    assert len(MODULES) > 150
    up = sorted(f"{mod} {_layer(mod)} imports {dep} {_layer(dep)}"
                for mod, path in MODULES.items() for dep in _imports(path, module_level_only=False)
                if _runs_up(mod, dep) and not (path.name == "__init__.py" and dep.startswith(mod + ".")))
    assert up == []


def test_the_sub_layers_are_told_apart() -> None:
    # batch's report draws with batch's own figures, which use the figures' saver: not the other way round
    assert _runs_up("tooltransfer.planner.apps.plots.save", "tooltransfer.planner.apps.batch.report")
    assert not _runs_up("tooltransfer.planner.apps.batch.figures", "tooltransfer.planner.apps.plots.save")
    assert _runs_up("tooltransfer.planner.apps.batch.runner", "tooltransfer.planner.apps.cli")
    assert _runs_up("tooltransfer.planner.learning.skills", "tooltransfer.planner.planning.solve")
    assert _runs_up("tooltransfer.planner.planning.solve", "tooltransfer.planner.execution.closed_loop")
    assert _runs_up("tooltransfer.planner.execution.simulate", "tooltransfer.planner.apps.cli")
    assert _runs_up("tooltransfer.planner.common.metric_units", "tooltransfer.planner.learning.skills")
    assert _runs_up("tooltransfer.timing", "tooltransfer.dmp")
    assert not _runs_up("tooltransfer.planner.planning.ss.opt_variant", "tooltransfer.planner.planning.oe.push_plan")


def test_every_planner_module_sits_in_a_sub_package() -> None:
    loose = sorted(p.name for p in (ROOT / "planner").glob("*.py") if p.name != "__init__.py")
    folders = sorted(p.name for p in (ROOT / "planner").iterdir() if p.is_dir() and p.name != "__pycache__")
    assert loose == []
    assert folders == sorted(PLANNER)


def test_no_shim() -> None:
    """No module (a package's __init__ aside) whose body is only imports and ``__all__``: a second path
    to another module's names."""
    shims = []
    for mod, path in MODULES.items():
        if path.name == "__init__.py":
            continue
        body = [n for n in ast.parse(path.read_text(encoding="utf-8")).body
                if not (isinstance(n, ast.Expr) and isinstance(n.value, ast.Constant))]
        if body and all(isinstance(n, ast.Import | ast.ImportFrom) or (
                isinstance(n, ast.Assign) and [getattr(t, "id", "") for t in n.targets] == ["__all__"]) for n in body):
            shims.append(mod)
    assert shims == []


def test_imports_have_no_circle() -> None:
    # every import counts, also one inside a function (a lazy import still ties the two modules together)
    graph = {mod: {d for d in _imports(path, module_level_only=False) if d != mod} for mod, path in MODULES.items()}
    # a package's __init__ importing its own submodules is not a circle of the submodules with it
    for mod in graph:
        graph[mod] = {d for d in graph[mod] if not (MODULES[mod].name == "__init__.py" and d.startswith(mod + "."))}
    try:
        list(TopologicalSorter(graph).static_order())
    except CycleError as exc:
        raise AssertionError(f"a circle of imports: {exc.args[1]}") from None
