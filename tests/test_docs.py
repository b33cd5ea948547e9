"""The documentation site builds without warnings, offline, and says what the code does; the licence,
citation and changelog agree with pyproject.toml."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
VERSION = PYPROJECT["project"]["version"]
PAPER_TITLE = ("A Novel Dynamic Movement Primitives-based Skill Learning and Transfer Framework for "
               "Multi-Tool Use")

needs_mkdocs = pytest.mark.skipif(
    importlib.util.find_spec("mkdocs") is None or importlib.util.find_spec("mkdocstrings_handlers") is None,
    reason="mkdocs and mkdocstrings[python] are not installed (pip install -e '.[docs]'; the test extra has them)",
)


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("site")
    proc = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file", str(ROOT / "mkdocs.yml"),
         "--site-dir", str(out)],
        cwd=ROOT, capture_output=True, text=True, timeout=300,
    )
    log = proc.stdout + proc.stderr
    assert proc.returncode == 0, log
    assert "WARNING" not in log, log
    return out


def _text(path: Path) -> str:
    return path.read_text(encoding="utf-8")


@needs_mkdocs
def test_every_page_is_built(site: Path) -> None:
    for page in ("index.html", "design/index.html", "planning/index.html", "mechanics/index.html",
                 "closed-loop/index.html", "formats/index.html", "examples/index.html", "api/index.html"):
        assert (site / page).stat().st_size > 5_000, page
    nav = yaml.safe_load(_text(ROOT / "mkdocs.yml"))["nav"]
    api = next(item["API reference"] for item in nav if "API reference" in item)
    modules = {next(iter(entry)) for entry in api} - {"Overview"}
    assert modules >= {"tooltransfer", "tooltransfer.dmp", "tooltransfer.dmp.qp", "tooltransfer.tools",
                       "tooltransfer.tools.pushing", "tooltransfer.tools.omni", "tooltransfer.planner.planning.solve",
                       "tooltransfer.planner.planning.plan", "tooltransfer.planner.planning.setting",
                       "tooltransfer.planner.execution.closed_loop",
                       "tooltransfer.planner.execution.plant", "tooltransfer.problems.task",
                       "tooltransfer.problems.dataset"}
    for module in modules:
        html = _text(site / "api" / module / "index.html")
        assert f'id="{module}' in html, module


@needs_mkdocs
def test_the_api_reference_documents_the_entry_points(site: Path) -> None:
    anchors = {
        "tooltransfer.planner.planning.solve": ["tooltransfer.planner.planning.solve.solve"],
        "tooltransfer.planner.execution.closed_loop": ["tooltransfer.planner.execution.closed_loop.execute_closed_loop",
                                             "tooltransfer.planner.execution.closed_loop.ClosedLoopReport"],
        "tooltransfer.planner.execution.plant": ["tooltransfer.planner.execution.plant.Plant",
                                           "tooltransfer.planner.execution.plant.ModelPlant",
                                           "tooltransfer.planner.execution.plant.SimPlant"],
        "tooltransfer.dmp.qp": ["tooltransfer.dmp.qp.solve_fit", "tooltransfer.dmp.qp.VelocityCone"],
        "tooltransfer.dmp": ["tooltransfer.dmp.DMP"],
        "tooltransfer.tools.pushing": ["tooltransfer.tools.pushing.mechanics.PushMechanics",
                                       "tooltransfer.tools.pushing.forward.simulate",
                                       "tooltransfer.tools.pushing.inverse.push_tool_path",
                                       "tooltransfer.tools.pushing.identify"],
        "tooltransfer.problems.task": ["tooltransfer.problems.task.load_task", "tooltransfer.problems.task.Task"],
        "tooltransfer.problems.dataset": ["tooltransfer.problems.dataset.load_dataset"],
        "tooltransfer.planner.planning.plan": ["tooltransfer.planner.planning.plan.read_plan",
                                               "tooltransfer.planner.planning.plan.Plan"],
        "tooltransfer.planner.planning.setting": ["tooltransfer.planner.planning.setting.Setting"],
        "tooltransfer.planner.planning.oe": ["tooltransfer.planner.planning.oe.condense_qp",
                                             "tooltransfer.planner.planning.oe.QPOptions"],
        "tooltransfer.planner.apps.batch": ["tooltransfer.planner.apps.batch.runner.run_batch",
                                            "tooltransfer.planner.apps.batch.spec.BatchSpec",
                                            "tooltransfer.planner.apps.batch.report.write_report"],
    }
    for module, ids in anchors.items():
        html = _text(site / "api" / module / "index.html")
        for ident in ids:
            assert f'id="{ident}"' in html, (module, ident)


@needs_mkdocs
def test_pages_carry_the_repository_text(site: Path) -> None:
    """The README and batch README sections, the design document and the schema table are in the pages."""
    mechanics = _text(site / "mechanics" / "index.html")
    assert "sticking while" in mechanics and "What to push." in mechanics
    assert "receding-horizon" in _text(site / "closed-loop" / "index.html")
    formats = _text(site / "formats" / "index.html")
    for needle in ("oe.friction_cone_fraction", "tooltransfer.dataset/1", "closed_loop_status",
                   "tooltransfer.skills/1", "tooltransfer.plan/1"):
        assert needle in formats, needle
    design = _text(site / "design" / "index.html")
    assert "Push mechanics: what the puck really does under a face" in design
    index = _text(site / "index.html")
    assert "teaches a robot to use a tool it has never seen" in index and "make demo" in index


@needs_mkdocs
def test_no_sphinx_role_markup_and_no_remote_assets(site: Path) -> None:
    """Sphinx roles of the docstrings become code (or links); the pages load nothing from the network."""
    remote = re.compile(r"""<(?:script|link|img)[^>]+(?:src|href)=["']https?://""")
    for page in site.rglob("*.html"):
        html = _text(page)
        assert not re.search(r":(?:func|mod|class|meth|data|attr|exc):<code>", html), page
        assert not remote.search(html), page


@needs_mkdocs
def test_the_maths_is_mathml_and_the_api_tables_read_right(site: Path) -> None:
    """Issue 29: equations are MathML written while building (no TeX left, no script), one attribute
    a row (``x_free`` and ``v_free`` apart), shapes with ``*`` not in italics."""
    design = _text(site / "design" / "index.html")
    assert design.count('<math xmlns="http://www.w3.org/1998/Math/MathML" display="block">') >= 6
    assert design.count('<math xmlns="http://www.w3.org/1998/Math/MathML" display="inline">') >= 20
    dmp = _text(site / "api" / "tooltransfer.dmp" / "index.html")
    assert dmp.count("<math ") >= 4 and "tooltransfer.dmp.coupling.obstacle_coupling" in dmp
    for page in site.rglob("*.html"):
        html = _text(page)
        assert 'class="arithmatex"' not in html and "\\(" not in html and "$$" not in html, page
        assert not re.search(r"<em>[a-z], [A-Z]</em>", html), page  # (T*n, N*n) read as italics
    assert 'title="tooltransfer.dmp.AffineRollout.x_free,"' not in dmp
    for name in ("x_free", "v_free"):
        assert f'title="tooltransfer.dmp.AffineRollout.{name}"' in dmp, name


def test_docs_pages_in_the_nav_exist() -> None:
    nav = yaml.safe_load(_text(ROOT / "mkdocs.yml"))["nav"]

    def pages(items: list) -> list[str]:
        out = []
        for item in items:
            value = next(iter(item.values()))
            out += pages(value) if isinstance(value, list) else [value]
        return out

    listed = pages(nav)
    assert all((ROOT / "docs" / p).is_file() for p in listed), listed
    on_disk = {p.relative_to(ROOT / "docs").as_posix() for p in (ROOT / "docs").rglob("*.md")}
    assert on_disk == set(listed), on_disk ^ set(listed)


def test_license_is_mit_and_ships_with_the_package() -> None:
    text = _text(ROOT / "LICENSE")
    assert text.startswith("MIT License") and "Copyright (c) 2026 the tooltransfer authors" in text
    assert PYPROJECT["project"]["license"] == "MIT"
    # setuptools (>= 77) puts LICEN[CS]E* into the wheel and the sdist unless license-files says otherwise
    floor = re.match(r"setuptools>=(\d+)", PYPROJECT["build-system"]["requires"][0])
    assert floor and int(floor[1]) >= 77
    files = PYPROJECT["project"].get("license-files")
    assert files is None or "LICENSE" in files


def test_citation_file_describes_the_software_and_the_paper() -> None:
    cff = yaml.safe_load(_text(ROOT / "CITATION.cff"))
    assert cff["cff-version"] == "1.2.0"
    assert cff["title"] == "tooltransfer" and cff["type"] == "software"
    assert str(cff["version"]) == VERSION, "CITATION.cff's version follows pyproject.toml"
    assert cff["license"] == "MIT"
    assert cff["authors"] and all("name" in a or "family-names" in a for a in cff["authors"])
    for key in ("message", "authors", "title"):
        assert cff[key]
    papers = [r for r in [*cff.get("references", []), cff.get("preferred-citation") or {}]
              if " ".join(str(r.get("title", "")).split()) == PAPER_TITLE]
    assert papers and all(p["type"] and p["authors"] for p in papers)


def test_changelog_has_this_version_and_unreleased() -> None:
    text = _text(ROOT / "CHANGELOG.md")
    assert "## [Unreleased]" in text
    assert re.search(rf"^## \[{re.escape(VERSION)}\] - \d{{4}}-\d{{2}}-\d{{2}}$", text, re.MULTILINE)


DESIGN_SECTION = re.compile(r"^## (\d+)\. \S", re.MULTILINE)
CITATION = re.compile(r"design\.md(?:\]\([^)\s]*\))?\s+(?:#\s*)?sections?\s+(\d+)(?:\s*-\s*(\d+))?")
CITING_SUFFIXES = {".py", ".md", ".yml", ".yaml", ".toml", ".cff", ".c"}


def _repository_texts() -> dict[str, str]:
    """The repository's text files by path (not build output, caches or the venv)."""
    skip = {".git", ".venv", "out", "site", "__pycache__", ".pytest_cache", ".ruff_cache", "build", "dist"}
    texts = {}
    for path in ROOT.rglob("*"):
        rel = path.relative_to(ROOT)
        if any(part in skip or part.endswith(".egg-info") for part in rel.parts):
            continue
        if path.is_file() and path.suffix in CITING_SUFFIXES:
            try:
                texts[rel.as_posix()] = _text(path)
            except UnicodeDecodeError:  # the hostile-input fixtures hold other encodings on purpose
                continue
    return texts


def test_design_sections_are_numbered_in_order() -> None:
    numbers = [int(n) for n in DESIGN_SECTION.findall(_text(ROOT / "docs" / "design.md"))]
    assert numbers == list(range(1, len(numbers) + 1)), numbers
    assert len(numbers) >= 10, numbers


def test_every_design_citation_names_a_section_that_exists() -> None:
    """A citation "docs/design.md section N" (or "sections N-M") in the code, the tests or the docs
    names a numbered section of docs/design.md; the old external steering file is not cited."""
    sections = {int(n) for n in DESIGN_SECTION.findall(_text(ROOT / "docs" / "design.md"))}
    texts = _repository_texts()
    cited, wrong = 0, []
    for rel, text in texts.items():
        for m in CITATION.finditer(text):
            lo = int(m[1])
            hi = int(m[2]) if m[2] else lo
            cited += 1
            if lo > hi or not set(range(lo, hi + 1)) <= sections:
                wrong.append(f"{rel}: {m[0]!r}")
        if rel != "tests/test_docs.py":
            assert not re.search(r"DESIGN\s+(?:#\s*)?section", text), f"{rel} cites the external DESIGN file"
    assert not wrong, wrong
    assert cited >= 40, cited


def test_the_citation_check_catches_a_missing_section() -> None:
    sections = {int(n) for n in DESIGN_SECTION.findall(_text(ROOT / "docs" / "design.md"))}
    missing = max(sections) + 1
    for text in (f"(docs/design.md section {missing})", f"docs/design.md sections 2-{missing}",
                 f"[docs/design.md](design.md) section {missing}", f"docs/design.md\n    # section {missing}"):
        m = CITATION.search(text)
        assert m, text
        hi = int(m[2] or m[1])
        assert not set(range(int(m[1]), hi + 1)) <= sections, text
