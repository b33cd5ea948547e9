"""Arrows point down (issue 17): tooltransfer.errors, .validation, .atomic and .versioned_json at the
bottom, then dmp, tools, problems, planner; no module imports one of a higher layer (also inside a
function), and the imports (at module level or inside a function) have no circle."""

from __future__ import annotations

import ast
from graphlib import CycleError, TopologicalSorter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LAYERS = {"errors": 0, "validation": 0, "atomic": 0, "versioned_json": 0,
          "dmp": 1, "tools": 2, "problems": 3, "planner": 4}


def _modules() -> dict[str, Path]:
    out = {}
    bottom = [ROOT / f"{name}.py" for name in ("errors", "validation", "atomic", "versioned_json")]
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


def _layer(module: str) -> int:
    return LAYERS[module.split(".")[1]]


def test_no_import_runs_up_the_layers() -> None:
    assert len(MODULES) > 150
    up = sorted(f"{mod} ({_layer(mod)}) imports {dep} ({_layer(dep)})"
                for mod, path in MODULES.items() for dep in _imports(path, module_level_only=False)
                if _layer(dep) > _layer(mod))
    assert up == []


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
