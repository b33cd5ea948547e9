"""Faces derived from a tool outline (tooltransfer.tools.derive, issue 28): the contacts' geometry,
the hand-annotated faces among them, outline input, tools and tasks without faces, the CLI."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import shapely
import yaml

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.cli import main
from tooltransfer.planner.planning.oe.face_frame import FaceFrame
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.problems.task import (
    MAX_SEARCH_STEPS,
    OEOptions,
    TaskFileError,
    push_search_steps,
    schema_default,
    task_from_dict,
    task_tool,
)
from tooltransfer.tools import OBJECT_RADIUS, DiscObject, load_library, load_tool, tool_to_dict
from tooltransfer.tools.derive import (
    CONTACT_WINDOW,
    MATCH_ANGLE,
    MAX_DERIVED_FACES,
    derive_faces,
    match_faces,
    outline_from,
    svg_polygon,
    with_derived_faces,
)
from tooltransfer.tools.library import library_has_faces, library_names
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.pose import wrap_angle

LIBRARY = load_library()
HAND = sorted(n for n in library_names() if library_has_faces(n))
BARE = sorted(n for n in library_names() if not library_has_faces(n))
ROOT = Path(__file__).resolve().parents[1]


def test_the_library_has_four_outline_only_tools() -> None:
    assert {"spatula", "rake", "cross_head", "rounded_pusher"} <= set(BARE)
    for name in BARE:
        assert LIBRARY[name].face_names and all(f.startswith("edge_") for f in LIBRARY[name].face_names)


@pytest.mark.parametrize("name", HAND)
def test_every_hand_face_is_a_derived_face(name: str) -> None:
    tool = LIBRARY[name]
    d = derive_faces(tool.outline, platform=OmniPlatform(a_t=tool.a_t))
    match = match_faces(tool.faces, d)
    assert None not in match.values(), match
    for f in tool.faces:
        g = next(x for x in d.faces if x.name == match[f.name])
        assert abs(wrap_angle(g.normal_angle - f.normal_angle)) <= MATCH_ANGLE
        # the hand face's contact part lies inside the edge's usable part (same edge, either direction)
        u = d.edge(g.name)
        e = u.end - u.start
        for p in f.contact_segment():
            s = float((p - u.start) @ e) / float(e @ e)
            assert u.contact_range[0] - 1e-3 <= s <= u.contact_range[1] + 1e-3, (f.name, s, u.contact_range)
        # the face's own range is the usable part, or its 12 mm nearest the tool centre point
        assert g.contact_range[0] >= u.contact_range[0] and g.contact_range[1] <= u.contact_range[1]
        assert (g.contact_range[1] - g.contact_range[0]) * g.length <= max(u.usable_length, CONTACT_WINDOW) + 1e-12


@pytest.mark.parametrize("name", sorted(LIBRARY))
def test_usable_parts_touch_without_overlap_and_are_maximal(name: str) -> None:
    tool = LIBRARY[name]
    r = OBJECT_RADIUS
    d = derive_faces(tool.outline)
    for e in d.edges:
        along = (e.end - e.start) / e.length
        for k, s in enumerate(e.contact_range):
            p = e.start + s * (e.end - e.start)
            assert tool.outline.distance(shapely.Point(p + r * e.normal)) >= r - 1e-12
            if 0.0 < s < 1.0:  # blocked there: 10 um further the disc overlaps the outline
                q = p + (-1 if k == 0 else 1) * 1e-5 * along
                assert tool.outline.distance(shapely.Point(q + r * e.normal)) < r - 1e-9
    derived = with_derived_faces(tool)
    setting = Setting(derived, OmniPlatform(a_t=tool.a_t), DiscObject(r))
    for f in derived.faces:  # every derived face is plannable: its frame builds on the Omni
        fr = FaceFrame.build(setting, f.name)
        assert fr.theta_b > 0.0 and fr.reach[0] > 0.0


def test_a_notch_narrower_than_the_object_is_not_a_face() -> None:
    rake = LIBRARY["rake"]
    names = {e.name for e in derive_faces(rake.outline).edges}
    assert not names & {"edge_5", "edge_6", "edge_7"}  # the teeth's inner sides and the notch bottom
    small = {e.name for e in derive_faces(rake.outline, object_radius=0.005).edges}
    assert {"edge_5", "edge_6", "edge_7"} <= small  # a 5 mm object reaches into it


def test_cone_travel_and_directions() -> None:
    tool = LIBRARY["finger"]
    plat = OmniPlatform(a_t=tool.a_t)
    d = derive_faces(tool.outline, friction=0.5, c=0.6, platform=plat)
    for f, e in zip(d.faces, d.edges, strict=True):
        assert f.theta_b == pytest.approx(np.arctan(0.5)) and f.push_angle == pytest.approx(e.normal_angle)
        assert e.travel == pytest.approx(e.usable_length * 0.36)
        lo, hi = e.world_directions
        assert hi - lo == pytest.approx(2 * np.arctan(0.5) + plat.limits.upper[0] - plat.limits.lower[0])
    convex = [v for v in d.vertices if v.normals[1] > v.normals[0]]
    assert len(convex) == 8  # every vertex of the finger is convex


def test_at_most_max_faces_and_the_search_bound_allows_them() -> None:
    oe = OEOptions()
    assert push_search_steps(MAX_DERIVED_FACES, oe.max_pushes, oe.segments) <= MAX_SEARCH_STEPS
    assert push_search_steps(MAX_DERIVED_FACES + 1, oe.max_pushes, oe.segments) > MAX_SEARCH_STEPS
    circle = shapely.Point(0, 0).buffer(0.02, quad_segs=8)  # 32 edges of 3.9 mm
    d = derive_faces(circle, platform=OmniPlatform())
    assert len(d.edges) > MAX_DERIVED_FACES == len(d.faces)
    assert schema_default(OEOptions, "max_pushes") == oe.max_pushes


def test_svg_paths_lines_arcs_and_curves() -> None:
    square = svg_polygon("M 0 0 h 10 v 10 H 0 Z")
    assert square.area == pytest.approx(1e-4) and square.bounds == pytest.approx((0, -0.01, 0.01, 0))
    tol = 1e-4
    disc = svg_polygon("M 10 0 A 10 10 0 1 1 -10 0 A 10 10 0 1 1 10 0 Z", arc_tolerance=tol)
    ring = np.asarray(disc.exterior.coords)
    assert np.allclose(np.hypot(*ring.T), 0.01)  # vertices on the circle, chords within tol of it
    half = np.arcsin(np.hypot(*np.diff(ring, axis=0).T).max() / 0.02)
    assert 0.01 * (1 - np.cos(half)) <= tol
    blob = svg_polygon("M 0 0 C 0 -10 20 -10 20 0 Q 10 20 0 0 z", arc_tolerance=1e-5)
    assert blob.is_valid and len(blob.exterior.coords) > 10
    with pytest.raises(InputError, match="one closed SVG subpath"):
        svg_polygon("M 0 0 L 1 0 L 1 1 Z M 5 5 L 6 5 L 6 6 Z")
    with pytest.raises(InputError, match="numbers after"):
        svg_polygon("M 0 0 L 1")


def test_outline_from_points_svg_and_tool_files(tmp_path: Path) -> None:
    pts = [[0.0, 0.0], [0.01, 0.0], [0.01, 0.01]]
    assert outline_from(pts).area == pytest.approx(5e-5)
    svg = tmp_path / "t.svg"
    svg.write_text('<svg xmlns="http://www.w3.org/2000/svg"><path d="M 0 0 L 10 0 L 10 10 Z"/></svg>')
    assert outline_from(svg).area == pytest.approx(5e-5)
    assert outline_from(ROOT / "tools" / "library" / "rake.yaml").equals(LIBRARY["rake"].outline)
    with pytest.raises(InputError, match="simple polygon"):
        outline_from([[0, 0], [1, 1], [1, 0], [0, 1]])


def test_derived_faces_replace_hand_faces_only_when_asked() -> None:
    finger = LIBRARY["finger"]
    assert finger.face_names == ("upper", "left")
    derived = with_derived_faces(finger)
    assert derived.outline.equals(finger.outline) and len(derived.faces) == 8


def test_a_task_inline_tool_without_faces_is_derived_for_the_task_object() -> None:
    data = yaml.safe_load((ROOT / "problems" / "paper" / "transfer_tool2.yaml").read_text())
    inline = tool_to_dict(load_tool("t_shape"))
    del inline["faces"]
    data["tool"] = inline
    task = task_from_dict(data, "inline")
    tool = task_tool(task)
    stem = next(f for f in tool.faces if f.name == "edge_7")
    data["object"] = {"radius": 0.01}
    smaller = task_tool(task_from_dict(data, "inline"))
    assert next(f for f in smaller.faces if f.name == "edge_7").contact_range[0] < stem.contact_range[0]
    data["tool"]["outline"] = [[0.0, 0.0], [0.001, 0.0], [0.001, 0.001]]  # no edge of 2 mm
    with pytest.raises(TaskFileError, match=r"tool\.outline"):
        task_from_dict(data, "inline")


def test_the_figure_draws_every_face(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    import matplotlib.pyplot as plt

    from tooltransfer.planner.apps.plots.derived_faces import draw_derivation

    d = derive_faces(LIBRARY["rake"].outline)
    fig, ax = plt.subplots()
    draw_derivation(ax, d)
    assert sorted(t.get_text() for t in ax.texts if t.get_text()) == sorted(f.name for f in d.faces)
    assert len(ax.patches) >= 1 + 2 * len(d.faces)  # the outline, and each face's object and cone
    plt.close(fig)


def test_cli_derive_writes_a_tool_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "rake.yaml"
    assert main(["tools", "derive", str(ROOT / "tools" / "library" / "rake.yaml"), "-o", str(out)]) == 0
    again = load_tool(out)
    assert again.face_names == LIBRARY["rake"].face_names
    capsys.readouterr()
    assert main(["tools", "derive", "M 0 0 L 30 0 L 30 20 L 0 20 Z", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["faces"] == ["edge_0", "edge_1", "edge_2", "edge_3"]  # a 30 x 20 mm box: every side
    assert doc["edges"][0]["contact_range"] == [0.0, 1.0] and len(doc["vertices"]) == 4
    assert main(["tools", "derive", "[[0, 0], [1]]"]) == 2
    assert main(["tools", "derive", str(tmp_path / "missing.svg")]) == 2


@pytest.mark.parametrize("name", ["spatula", "rake", "cross_head", "rounded_pusher"])
def test_outline_only_tools_plan_and_execute_open_loop(name: str) -> None:
    """Derive, plan and execute on the MuJoCo platform: a 30 mm push to the left with each new tool
    (at most two pushes: the search stays small)."""
    pytest.importorskip("mujoco")
    from tooltransfer.planner.execution.simulate import simulate_plan
    from tooltransfer.planner.planning.solve import solve

    task = task_from_dict({"format": "tooltransfer.task/1", "name": f"derived_{name}", "tool": name,
                           "start": [0.0, 0.15], "target": [-0.03, 0.154],
                           "skills": {"dataset": str(ROOT / "problems" / "data" / "finger_demos")},
                           "variants": {"oe": "qp", "ss": "arch"}, "oe": {"max_pushes": 2}}, name)
    plan = solve(task)
    assert plan.status == "solved", plan.reason
    used = {f for f in plan.face if f}
    assert used and used <= set(LIBRARY[name].face_names)
    assert {f["name"] for f in plan.tool["faces"]} == set(LIBRARY[name].face_names)
    assert all(set(f) == {"name", "segment", "push_angle", "theta_b", "contact_range"} for f in plan.tool["faces"])
    assert simulate_plan(plan).final_error < 0.005
