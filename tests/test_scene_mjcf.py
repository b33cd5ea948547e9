"""`tooltransfer mjcf TASK|PLAN -o scene.xml` writes a scene MuJoCo loads (tool, puck, obstacles, target,
a start keyframe); `simulate --viewer` without a display stops at once with exit 2 and one line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from tooltransfer.planner.apps.cli import main  # noqa: E402
from tooltransfer.problems.task import load_task  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TASK = ROOT / "problems" / "paper" / "transfer_tool2.yaml"


@pytest.fixture(scope="module")
def plan_path(transfer_plan_file: Path) -> Path:
    """The transfer task's plan file (tests/conftest.py), solved once for the session."""
    return transfer_plan_file


def _loaded(path: Path) -> tuple[object, object]:
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("start").id)
    mujoco.mj_forward(model, data)
    return model, data


def _geoms(model: object) -> set[str]:
    return {model.geom(i).name for i in range(model.ngeom)}  # type: ignore[attr-defined]


def test_mjcf_of_a_task_loads_with_tool_puck_obstacles_and_target(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "scene.xml"
    assert main(["mjcf", "paper/transfer_tool2", "-o", str(out)]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    model, data = _loaded(out)
    task = load_task(TASK)
    names = _geoms(model)
    assert {"puck", "table", "tool_piece0"} <= names
    assert sum(n.startswith("obstacle") for n in names) == len(task.obstacles) == 1
    np.testing.assert_allclose(data.body("puck").xpos[:2], task.start, atol=1e-12)  # type: ignore[attr-defined]
    np.testing.assert_allclose(data.site("target").xpos[:2], task.target, atol=1e-12)  # type: ignore[attr-defined]
    np.testing.assert_allclose(data.geom("obstacle0").xpos[:2], task.obstacles[0].centre, atol=1e-12)  # type: ignore[attr-defined]


def test_mjcf_of_a_plan_starts_the_arm_at_the_plans_joints(plan_path: Path, tmp_path: Path) -> None:
    from tooltransfer.planner.planning.plan import read_plan

    out = tmp_path / "scene.xml"
    assert main(["mjcf", str(plan_path), "-o", str(out)]) == 0
    model, data = _loaded(out)
    plan = read_plan(plan_path)
    q = [data.joint(n).qpos[0] for n in ("q1", "q2", "q3")]  # type: ignore[attr-defined]
    np.testing.assert_allclose(q, plan.joints[0], atol=1e-12)
    # the model is the one the simulation runs: the same geoms, plus the target's site
    assert any(n.startswith("tool_piece") for n in _geoms(model))
    tcp = data.body("tcp_row").xpos[:2]  # type: ignore[attr-defined]
    np.testing.assert_allclose(tcp, plan.tool_pose[0, :2], atol=1e-4)


def test_mjcf_names_a_bad_source(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["mjcf", "no/such_task", "-o", str(tmp_path / "scene.xml")]) == 2
    err = capsys.readouterr().err
    assert "no/such_task" in err and "Traceback" not in err
    assert not (tmp_path / "scene.xml").exists()


def test_viewer_without_a_display_stops_before_any_work(
    plan_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr("sys.platform", "linux")
    assert main(["simulate", str(plan_path), "--viewer"]) == 2
    captured = capsys.readouterr()
    assert "--viewer" in captured.err and "DISPLAY" in captured.err and "Traceback" not in captured.err
    assert "final_error" not in captured.out  # refused before simulating


def test_the_viewer_runs_the_simulation_the_report_gives(plan_path: Path) -> None:
    """What `simulate --viewer` steps (the written scene from its keyframe, the plan's controls) ends
    with the puck where the open-loop simulation puts it: the window shows the run that was reported."""
    from tooltransfer.planner.execution.scene import viewer_run
    from tooltransfer.planner.execution.simulate import simulate_plan
    from tooltransfer.planner.planning.plan import read_plan

    plan = read_plan(plan_path)
    model, data, controls = viewer_run(plan)
    for ctrl in controls:
        data.ctrl[:] = ctrl
        mujoco.mj_step(model, data)
    report = simulate_plan(plan)
    np.testing.assert_allclose(data.body("puck").xpos[:2], report.execution.object_xy[-1], rtol=0, atol=1e-6)
