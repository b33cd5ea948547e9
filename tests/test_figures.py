"""Looking rather than reading (issue 18, point 7): the README shows Fig. 12 of the transfer task
and the variant comparison as committed images that ``make figures`` redraws; every figure draws
lengths in mm; the comparison's panels (and Fig. 12's) share their axes."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
TRANSFER = ROOT / "problems" / "paper" / "transfer_tool2.yaml"
DATASET = ROOT / "problems" / "data" / "finger_demos"


def test_the_readme_shows_the_committed_figures() -> None:
    from tooltransfer.planner.apps.plots.paper_figures import README_FIGURES

    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    shown = re.findall(r"!\[[^\]]+\]\((docs/images/[^)]+\.png)\)", readme)
    assert shown == [f"docs/images/{name}" for name in README_FIGURES]
    for rel in shown:
        data = (ROOT / rel).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and 10_000 < len(data) < 300_000, (rel, len(data))
    make = (ROOT / "Makefile").read_text(encoding="utf-8")
    recipe = r"^figures: .*\n(\t.*\n)*\t\$\(PY\) -m tooltransfer\.planner\.apps\.plots\.paper_figures docs/images$"
    assert re.search(recipe, make, re.MULTILINE)
    assert "<!-- include: README.md | Two figures" in (ROOT / "docs" / "index.md").read_text(encoding="utf-8")


@pytest.fixture
def drawn(monkeypatch: pytest.MonkeyPatch) -> list:
    """The matplotlib figures saved while the test runs (their axes are inspected)."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    figures: list = []
    save = Figure.savefig

    def keep(self, *args, **kwargs):  # type: ignore[no-untyped-def]
        figures.append(self)
        return save(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", keep)
    return figures


def _labels(fig) -> list[str]:  # type: ignore[no-untyped-def]
    return [text for ax in fig.axes for text in (ax.get_xlabel(), ax.get_ylabel()) if text]


@pytest.fixture(scope="module")
def plans() -> dict:
    from tooltransfer.planner.planning.solve import solve
    from tooltransfer.problems import PAPER_PAIRS as PAIRS
    from tooltransfer.problems.task import load_task

    task = load_task(TRANSFER)
    out = {}
    for oe, ss in PAIRS:
        t = task.model_copy(update={"variants": task.variants.model_copy(update={"oe": oe, "ss": ss})})
        out[f"{oe}/{ss}"] = solve(t, TRANSFER)
    assert out["qp/opt"].status == "solved"
    return out


def test_every_figure_draws_lengths_in_mm(tmp_path: Path, drawn: list, plans: dict) -> None:
    from tooltransfer.planner.apps.plots import paper_figures as figures
    from tooltransfer.planner.learning.skills import learn_skills

    skills = learn_skills(DATASET)
    figures.fig8(DATASET, skills, tmp_path)
    figures.fig10(TRANSFER, tmp_path / "fig10.png")
    figures.fig11(skills, tmp_path / "fig11.png")
    figures.fig14(ROOT / "problems" / "paper" / "fig14_safety_margin.yaml", tmp_path / "fig14.png")
    figures.fig12(plans["qp/opt"], tmp_path / "fig12.png")
    from tooltransfer.planner.apps.plots.execution import plot_plans

    plot_plans(plans, tmp_path / "compare.png")
    assert len(drawn) == 7
    for fig in drawn:
        labels = _labels(fig)
        assert not [x for x in labels if "[m]" in x], labels
        assert any("x [mm]" in x for x in labels) and any("y [mm]" in x for x in labels), labels
    # Fig. 8a: the demonstrations' tracks are drawn in mm (the start near (45, 120) mm)
    ax = drawn[0].axes[0]
    xs = np.concatenate([line.get_xdata() for line in ax.get_lines() if len(line.get_xdata())])
    assert 20 < np.median(np.abs(xs)) < 200


def test_the_compare_panels_and_fig12_share_their_axes(tmp_path: Path, drawn: list, plans: dict) -> None:
    from tooltransfer.planner.apps.plots.execution import plot_plan, plot_plans

    plot_plans(plans, tmp_path / "compare.png")
    plot_plan(plans["qp/opt"], tmp_path / "fig12.png")
    for fig in drawn:
        axes = [ax for ax in fig.axes if ax.get_visible()]
        assert len(axes) >= 1
        first = axes[0]
        for ax in axes[1:]:
            assert first.get_shared_x_axes().joined(first, ax) and first.get_shared_y_axes().joined(first, ax)
            assert ax.get_xlim() == first.get_xlim() and ax.get_ylim() == first.get_ylim()
    # an infeasible pair is drawn with its reason, not left blank
    texts = [t.get_text() for ax in drawn[0].axes for t in ax.texts]
    infeasible = [name for name, p in plans.items() if p.status == "infeasible"]
    assert len([t for t in texts if t]) >= len(infeasible)


def test_make_figures_writes_small_palette_images(tmp_path: Path) -> None:
    from PIL import Image

    from tooltransfer.planner.apps.plots.paper_figures import README_FIGURES, readme_figures

    paths = readme_figures(tmp_path)
    assert [p.name for p in paths] == list(README_FIGURES)
    for p in paths:
        assert p.stat().st_size < 300_000
        with Image.open(p) as im:
            assert im.mode == "P" and im.size[0] >= 1000


def test_fig12_says_what_it_draws_and_keeps_its_labels(tmp_path: Path, drawn: list, plans: dict) -> None:
    """Issue 29: the x label inside the saved image, the four phases in four colours, the scene in the
    legend, each face's name clear of the outline it names."""
    import shapely
    from PIL import Image

    from tooltransfer.planner.apps.plots.execution import plot_plan

    out = plot_plan(plans["qp/opt"], tmp_path / "fig12.png", dpi=100)
    fig = drawn[0]
    ax = fig.axes[0]
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert {"obstacle", "safety margin", "puck (start)", "target", "tool (approach)", "tool (retreat)"} <= set(legend)
    colours = {line.get_label(): line.get_color() for line in ax.get_lines()}
    phases = [colours[f"tool ({p})"] for p in ("approach", "push", "switch", "retreat")]
    assert len(set(phases)) == 4, phases
    # the saved area is the drawn content: its size is the tight box's, and the x labels lie inside it
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    renderer = FigureCanvasAgg(fig).get_renderer()  # the saved figure was closed: a canvas to measure on
    box = fig.get_tightbbox(renderer).padded(0.05)
    with Image.open(out) as im:
        assert abs(im.size[0] - box.width * 100) <= 2 and abs(im.size[1] - box.height * 100) <= 2
    for a in fig.axes:
        label = a.xaxis.label.get_window_extent(renderer).transformed(fig.dpi_scale_trans.inverted())
        assert box.x0 <= label.x0 and label.x1 <= box.x1 and box.y0 <= label.y0 and label.y1 <= box.y1
    # each push's outline (blue, closed) is followed by its face's name: the text's box misses the outline
    outlines = [line for line in ax.get_lines()
                if line.get_color() == "tab:blue" and line.get_marker() == "None" and len(line.get_xdata()) > 3]
    names = [t for t in ax.texts if t.get_text()]
    assert len(outlines) == len(names) == len(plans["qp/opt"].pushes) > 0
    to_data = ax.transData.inverted()
    for line, text in zip(outlines, names, strict=True):
        corners = to_data.transform(text.get_window_extent(renderer).get_points())
        label_box = shapely.box(*corners[0], *corners[1])
        outline = shapely.Polygon(np.column_stack([line.get_xdata(), line.get_ydata()]))
        assert not label_box.intersects(outline), text.get_text()


def test_the_batch_box_plot_draws_every_run_once(tmp_path: Path, drawn: list) -> None:
    """Issue 29: a small batch's runs are dots beside quartile boxes with 1.5 IQR whiskers (no run
    drawn as an outlier as well), and the title says so."""
    from tooltransfer.planner.apps.batch.figures import plot_batch

    times = [0.41, 0.52, 0.47, 2.9, 0.5]
    rows = [{"variant": "qp/opt", "status": "solved", "time_total": t, "n_obstacles": 1, "reach_margin": 0.01 * i}
            for i, t in enumerate(times)]
    plot_batch(rows, tmp_path)
    fig = next(f for f in drawn if "planning time" in f.axes[0].get_title())
    ax = fig.axes[0]
    assert "1.5 IQR" in ax.get_title() and "percentile" not in ax.get_title()
    dots = [line for line in ax.get_lines() if line.get_marker() == "." and len(line.get_ydata())]
    assert len(dots) == 1 and sorted(dots[0].get_ydata()) == sorted(1e3 * np.array(times))
    fliers = [line for line in ax.get_lines() if line.get_marker() not in ("None", "", ".") and len(line.get_ydata())]
    assert not fliers
