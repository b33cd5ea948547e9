"""One import name (issue 17): the repository's root is the package ``tooltransfer`` and its folders
``dmp/``, ``tools/``, ``planner/``, ``problems/`` its subpackages; ``import tooltransfer as tt`` gives what a
user needs first, from any folder; nothing else is installed, and no file of the project imports the
folders by their bare names (a second copy of every module, with its own classes, would load)."""

from __future__ import annotations

import re
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("dmp", "tools", "planner", "problems")
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))


def test_the_package_list_is_every_folder_of_the_four() -> None:
    setuptools = PYPROJECT["tool"]["setuptools"]
    assert setuptools["package-dir"] == {"tooltransfer": "."}
    folders = {"tooltransfer"} | {
        "tooltransfer." + ".".join(d.relative_to(ROOT).parts)
        for pkg in PACKAGES for d in [ROOT / pkg, *(ROOT / pkg).rglob("*")]
        if d.is_dir() and d.name != "__pycache__"
    }
    assert set(setuptools["packages"]) == folders
    assert PYPROJECT["project"]["scripts"] == {"tooltransfer": "tooltransfer.planner.apps.cli:main"}


def test_the_entry_point_from_another_folder(tmp_path: Path) -> None:
    code = (
        "import importlib.util, json, sys\n"
        "import tooltransfer as tt\n"
        f"task = tt.load_task({str(ROOT / 'problems' / 'paper' / 'transfer_tool2.yaml')!r})\n"
        "plan = tt.solve(task)\n"
        "assert isinstance(plan, tt.Plan) and issubclass(tt.InputError, tt.ToolTransferError)\n"
        "bare = [m for m in ('dmp', 'tools', 'planner', 'problems') if importlib.util.find_spec(m) is not None]\n"
        "tops = {m.split('.')[0] for m in sys.modules}\n"
        "loaded = sorted(tops & {'dmp', 'tools', 'planner', 'problems'})\n"
        "print(json.dumps([plan.status, tt.__version__, sorted(tt.__all__), bare, loaded]))\n"
    )
    run = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                         check=False)
    assert run.returncode == 0, run.stderr[-3000:]
    import json

    status, version, names, bare, loaded = json.loads(run.stdout.splitlines()[-1])
    assert status == "solved"
    assert version == PYPROJECT["project"]["version"]
    assert set(names) >= {"load_task", "solve", "read_plan", "Plan", "DMP", "ToolTransferError", "__version__"}
    assert bare == [] and loaded == []  # nothing outside tooltransfer is importable or imported


def test_importing_tooltransfer_is_light() -> None:
    """The entry point imports its names on first use: ``import tooltransfer`` (which every command and
    subpackage import runs first) loads no numpy, pydantic or solver."""
    code = ("import sys, tooltransfer\n"
            "print(sorted(m for m in ('numpy', 'pydantic', 'scipy', 'casadi') if m in sys.modules))")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True)
    assert run.stdout.strip() == "[]"


_BARE = re.compile(r"^\s*(?:from|import)\s+(dmp|tools|planner|problems)\b", re.MULTILINE)
_STRING = re.compile(r"""["'`](?:-m )?(dmp|tools|planner|problems)\.[a-z_]+[a-z_.]*(?::\w+)?["'`]""")


def test_no_file_uses_the_bare_names() -> None:
    files = [p for p in ROOT.rglob("*") if p.suffix in (".py", ".md", ".toml", ".yml", ".cfg")
             and not {".venv", ".venv-lowest", "out", "build", ".git"} & set(p.relative_to(ROOT).parts)
             and p.name != "CHANGELOG.md" and ".egg-info" not in str(p)]
    assert len(files) > 150
    offenders = []
    for p in files:
        text = p.read_text(encoding="utf-8")
        for rx in (_BARE, _STRING):
            for m in rx.finditer(text):
                module = m.group(0).strip("\"'` ").removeprefix("-m ").split(":")[0]
                if rx is _STRING and not (ROOT / m.group(1) / module.split(".")[1]).exists() and not (
                        ROOT / m.group(1) / (module.split(".")[1] + ".py")).exists():
                    continue  # an attribute of a variable named like a package (``dmp.tau``), not a module
                offenders.append(f"{p.relative_to(ROOT)}: {m.group(0).strip()}")
    assert offenders == []
