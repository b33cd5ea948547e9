"""``tooltransfer view``: the transfer plan (and its open-loop execution, recorded by ``simulate
--record``) as a page, checked in headless Chromium: no console error, the slider moves the puck to
the plan's positions, the executed path is drawn beside the planned one; bad recordings are refused
naming the file and the field."""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import pytest
from browser import browser, console_errors, open_page

from tooltransfer.planner.apps.cli import main
from tooltransfer.planner.planning.plan import Plan, read_plan

TASK = "paper/transfer_tool2"


@pytest.fixture(scope="module")
def pages(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The plan, its open-loop recording and both pages (without and with the execution)."""
    pytest.importorskip("mujoco", reason="the sim extra (mujoco) is not installed")
    tmp = tmp_path_factory.mktemp("view")
    assert main(["solve", TASK, "-o", str(tmp / "plan.json")]) == 0
    assert main(["simulate", str(tmp / "plan.json"), "--record", str(tmp / "rec.json")]) == 0
    assert main(["view", str(tmp / "plan.json"), "-o", str(tmp / "plain.html")]) == 0
    assert main(["view", str(tmp / "plan.json"), "--execution", str(tmp / "rec.json"), "-o",
                 str(tmp / "plan.html")]) == 0
    # a plan without a path (the solved plan's task, tool and obstacles; status infeasible, no samples)
    solved = read_plan(tmp / "plan.json")
    Plan(status="infeasible", variant=solved.variant, task=solved.task, platform=solved.platform,
         object=solved.object, tool=solved.tool, obstacles=solved.obstacles,
         reason="certified infeasible: <b>no</b> face reaches the target").write(tmp / "none.json")
    assert main(["view", str(tmp / "none.json"), "-o", str(tmp / "none.html")]) == 0
    return tmp


def test_recording_holds_the_execution(pages: Path) -> None:
    rec = json.loads((pages / "rec.json").read_text())
    assert rec["format"] == "tooltransfer.recording/1" and list(rec["executions"]) == ["open loop"]
    e = rec["executions"]["open loop"]
    plan = read_plan(pages / "plan.json")
    assert len(e["t_object"]) == len(e["object_xy"]) > 10 and len(e["t_tool"]) == len(e["tool_pose"]) > 10
    # the executed object ends near the planned end (the open loop executes this plan to about 1 mm)
    assert np.linalg.norm(np.array(e["object_xy"][-1]) - plan.object_xy[-1]) < 5e-3


@pytest.mark.parametrize("content, field", [
    ("[1, 2]", "format"), ('{"format": "other"}', "format"),
    ('{"format": "tooltransfer.recording/1", "executions": {"open loop": {"t_object": [0, 1], '
     '"object_xy": [[0, 0]], "t_tool": [], "tool_pose": []}}}', "executions.open loop"),
    ('{"format": "tooltransfer.recording/1", "executions": {"x": {"t_object": ["a"]}}}', "t_object"),
])
def test_bad_recordings_are_refused_naming_the_field(pages: Path, tmp_path: Path, capsys: pytest.CaptureFixture,
                                                     content: str, field: str) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text(content)
    assert main(["view", str(pages / "plan.json"), "--execution", str(bad), "-o", str(tmp_path / "x.html")]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and field in err and "Traceback" not in err
    assert not (tmp_path / "x.html").exists()


def test_view_in_chromium_moves_the_puck_along_the_plan(pages: Path) -> None:
    plan = read_plan(pages / "plan.json")
    with browser() as d:
        open_page(d, pages / "plan.html", "window.ttReady")
        assert console_errors(d) == []
        names = d.execute_script("return document.getElementById('plan').data.map(t => t.name)")
        assert {"planned object path", "executed object path, open loop", "tool", "puck (plan)",
                "face in contact"} <= set(names)
        assert any(n.startswith("switches") for n in names) and any(n.startswith("re-contacts") for n in names)
        meta = d.execute_script("return document.getElementById('plan').layout.meta")
        index = meta["frame_index"]
        assert index[0] == 0 and index[-1] == len(plan.t) - 1
        from selenium.webdriver.common.action_chains import ActionChains

        rail = d.find_element("css selector", ".slider-rail-touch-rect")
        for fraction in (0.3, 0.8, 0.0):  # click the slider's rail: the puck goes to the plan's position then
            ActionChains(d).move_to_element_with_offset(rail, int((fraction - 0.5) * rail.size["width"]), 0) \
                .click().perform()
            deadline = time.monotonic() + 5.0
            while True:
                k, xs, ys = d.execute_script(
                    "var gd = document.getElementById('plan'); var t = gd.data[gd.layout.meta.puck_trace];"
                    "return [gd._fullLayout.sliders[0].active, t.x, t.y]")
                centre = np.array([np.mean(xs[:-1]), np.mean(ys[:-1])]) / 1e3
                if np.allclose(centre, plan.object_xy[index[k]], atol=1e-5) or time.monotonic() > deadline:
                    break
                time.sleep(0.05)
            assert abs(k - fraction * (len(index) - 1)) <= 0.02 * len(index)
            assert centre == pytest.approx(plan.object_xy[index[k]], abs=1e-5)
        # play: the puck moves on its own
        d.execute_script("Array.from(document.querySelectorAll('.updatemenu-button'))"
                         ".find(b => b.textContent === 'play').dispatchEvent(new MouseEvent('click'))")
        time.sleep(1.0)
        assert d.execute_script("return document.getElementById('plan')._fullLayout.sliders[0].active") > 0
        assert console_errors(d) == []
        # a plan without a path: the scene, the reason as text, no slider
        open_page(d, pages / "none.html", "window.ttReady")
        assert d.execute_script("return document.getElementById('reason').textContent") == \
            "certified infeasible: <b>no</b> face reaches the target"
        assert d.execute_script("return document.querySelectorAll('.slider-rail-touch-rect').length") == 0
        assert console_errors(d) == []


def test_view_writes_a_page_without_execution(pages: Path) -> None:
    text = (pages / "plain.html").read_text()
    assert "executed object path" not in text and "planned object path" in text
    assert "<script src=" not in text  # plotly.js inlined: nothing fetched at view time


def test_view_without_plotly_names_the_extra(pages: Path, tmp_path: Path) -> None:
    import subprocess
    import sys

    code = ("import sys\nsys.modules['plotly'] = None\nfrom tooltransfer.planner.apps.cli import main\n"
            f"sys.exit(main(['view', {str(pages / 'plan.json')!r}, '-o', 'x.html']))\n")
    run = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=120,
                         check=False)
    assert run.returncode == 2 and "tooltransfer[report]" in run.stderr and "Traceback" not in run.stderr
    assert not (tmp_path / "x.html").exists()
