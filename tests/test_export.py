"""Plans a real arm can run (issue 18, point 5): the plan's joint velocities and accelerations are the
derivatives of its joints on its times (the simulated execution's feed-forward, and through the
Omni's Jacobian the tool path's velocity); ``read_plan`` validates them and derives them for plan
files written before them; ``tooltransfer export`` writes CSV, ``.npz`` and a ROS JointTrajectory
as JSON, each read back to the plan's arrays, with the command line's usual errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tooltransfer.planner.apps.cli import main
from tooltransfer.planner.execution.export import (
    FORMATS,
    SUFFIXES,
    Trajectory,
    export_plan,
    joint_trajectory_message,
    joint_trajectory_text,
    read_trajectory,
)
from tooltransfer.planner.execution.simulate import check_plan
from tooltransfer.planner.planning.plan import JOINT_NAMES, Plan, PlanFileError, joint_rates, read_plan

ROOT = Path(__file__).resolve().parents[1]
TASK = ROOT / "problems" / "paper" / "transfer_tool2.yaml"


@pytest.fixture(scope="module")
def plan_path(transfer_plan_file: Path) -> Path:
    """The transfer task's plan file (tests/conftest.py), solved once for the session."""
    return transfer_plan_file


@pytest.fixture(scope="module")
def plan(plan_path: Path) -> Plan:
    return read_plan(plan_path)


def _edited(tmp: Path, plan_path: Path, edit) -> Path:  # type: ignore[no-untyped-def]
    d = json.loads(plan_path.read_text())
    edit(d)
    out = tmp / "edited.json"
    out.write_text(json.dumps(d))
    return out


# --- the plan's joint rates -----------------------------------------------------------------------

def test_joint_rates_are_the_derivatives_on_an_uneven_grid() -> None:
    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0.008, 0.012, 400))
    q = np.column_stack([np.sin(2 * t), 0.3 * np.cos(t), t**2 / 10])
    v, a = joint_rates(t, q)
    dv = np.column_stack([2 * np.cos(2 * t), -0.3 * np.sin(t), t / 5])
    da = np.column_stack([-4 * np.sin(2 * t), -0.3 * np.cos(t), np.full_like(t, 0.2)])
    inner = slice(2, -2)  # one-sided (first order) at the ends
    assert np.abs(v - dv)[inner].max() < 1e-3 and np.abs(a - da)[inner].max() < 1e-2
    assert joint_rates(t[:1], q[:1])[0].tolist() == [[0.0, 0.0, 0.0]]


def test_the_plan_carries_its_joint_rates_and_names(plan: Plan) -> None:
    assert plan.joint_velocities.shape == plan.joints.shape == plan.joint_accelerations.shape
    assert plan.joint_names == JOINT_NAMES
    v, a = joint_rates(plan.t, plan.joints)
    np.testing.assert_array_equal(plan.joint_velocities, v)
    np.testing.assert_array_equal(plan.joint_accelerations, a)
    # what the simulated execution feeds forward when it is given no velocities
    from tooltransfer.problems.task import task_from_dict, task_platform, task_tool
    from tooltransfer.tools.sim.reference import joint_reference

    task = task_from_dict(plan.task)
    platform = task_platform(task, task_tool(task))
    ref = joint_reference(plan.t, plan.joints, None, 0.002, platform)
    mine = joint_reference(plan.t, plan.joints, plan.joint_velocities, 0.002, platform)
    np.testing.assert_array_equal(ref.qd, mine.qd)
    # the plan starts and ends at rest; the Omni's joints stay within a few rad/s and tens of rad/s^2
    assert np.abs(v[[0, -1]]).max() < 2e-3 and np.abs(v).max() < 2.0 and np.abs(a).max() < 100.0


def test_through_the_jacobian_the_joint_velocities_give_the_tool_velocity(plan: Plan) -> None:
    from tooltransfer.planner.learning.segmentation.geometry import table_poses

    p = plan.platform

    def fk(q: np.ndarray) -> np.ndarray:
        return table_poses(q, p["a_t"], p["base_xy"], p["base_yaw"], p["table_height"])[:, :2]

    h = 1e-7
    jac = np.stack([(fk(plan.joints + h * e) - fk(plan.joints - h * e)) / (2 * h) for e in np.eye(3)], axis=-1)
    tool_v = np.einsum("kij,kj->ki", jac, plan.joint_velocities)
    want = np.gradient(plan.tool_pose[:, :2], plan.t, axis=0)  # the timed tool path's velocity
    speed = np.linalg.norm(want, axis=1).max()
    assert 0.03 < speed < 0.06  # [m/s] the task's limit is 50 mm/s
    assert np.linalg.norm(tool_v - want, axis=1).max() < 1e-3 * speed


def test_integrated_the_rates_give_the_joints_back(plan: Plan) -> None:
    """Trapezoids of the velocities over the plan's times reproduce the joints (the plan's corners,
    where the velocity changes within a sample, cost a little), and of the accelerations the velocities."""
    dt = np.diff(plan.t)[:, None]

    def integral(y: np.ndarray) -> np.ndarray:
        return np.vstack([np.zeros((1, 3)), np.cumsum(0.5 * (y[1:] + y[:-1]) * dt, axis=0)])

    q, v = plan.joints, plan.joint_velocities
    assert np.abs(integral(v) - (q - q[0])).max() < 3e-3  # [rad] over 20 s; the joints move about 1 rad
    assert np.abs(integral(plan.joint_accelerations) - (v - v[0])).max() < 0.1 * np.abs(v).max()
    steps = np.abs(0.5 * (v[1:] + v[:-1]) * dt - np.diff(q, axis=0))
    assert np.median(steps) < 1e-6


# --- plan files -------------------------------------------------------------------------------------

def test_the_rates_are_written_and_read_back(plan: Plan, plan_path: Path) -> None:
    doc = json.loads(plan_path.read_text())
    assert doc["joint_names"] == list(JOINT_NAMES)
    assert len(doc["samples"]["joint_velocities"]) == len(doc["samples"]["t"]) == len(
        doc["samples"]["joint_accelerations"])
    np.testing.assert_array_equal(np.array(doc["samples"]["joint_accelerations"]), plan.joint_accelerations)


def test_an_older_plan_file_without_them_is_read_with_them_derived(plan: Plan, plan_path: Path,
                                                                   tmp_path: Path) -> None:
    def strip(d: dict) -> None:
        del d["joint_names"], d["samples"]["joint_velocities"], d["samples"]["joint_accelerations"]

    old = read_plan(_edited(tmp_path, plan_path, strip))
    assert old.joint_names == JOINT_NAMES
    np.testing.assert_array_equal(old.joint_velocities, plan.joint_velocities)
    np.testing.assert_array_equal(old.joint_accelerations, plan.joint_accelerations)
    check_plan(old, "old.json")


def _set(key: str, index: tuple[int, ...], value: object):  # type: ignore[no-untyped-def]
    def edit(d: dict) -> None:
        node = d["samples"][key] if key in d["samples"] else d[key]
        for i in index[:-1]:
            node = node[i]
        node[index[-1]] = value
    return edit


READ_CASES = {
    "a velocity a string": (_set("joint_velocities", (5, 1), "0.3"), "samples.joint_velocities[5][1]", "a number"),
    "a velocity NaN": (_set("joint_velocities", (9, 0), float("nan")), "samples.joint_velocities[9][0]", "finite"),
    "an acceleration true": (_set("joint_accelerations", (3, 2), True), "samples.joint_accelerations[3][2]",
                             "rad/s^2"),
    "an acceleration huge": (_set("joint_accelerations", (7, 0), 1e300), "samples.joint_accelerations[7][0]",
                             "within"),
    "a row of 2 velocities": (_set("joint_velocities", (4,), [0.1, 0.2]), "samples.joint_velocities[4]",
                              "3 numbers"),
    "velocities cut short": (lambda d: d["samples"]["joint_velocities"].pop(), "samples.joint_velocities",
                             "entries like samples.t"),
    "velocities a mapping": (lambda d: d["samples"].update(joint_velocities={}), "samples.joint_velocities", "list"),
    "two joint names": (lambda d: d.update(joint_names=["a", "b"]), "joint_names", "3 joint names"),
    "a joint name a number": (lambda d: d.update(joint_names=["a", 2, "c"]), "joint_names[1]", "printable"),
    "a joint name twice": (lambda d: d.update(joint_names=["a", "b", "a"]), "joint_names", "distinct"),
    "an empty joint name": (lambda d: d.update(joint_names=["a", "", "c"]), "joint_names[1]", "1 to 100"),
}


@pytest.mark.parametrize("name", sorted(READ_CASES))
def test_read_plan_validates_the_new_fields(plan_path: Path, tmp_path: Path, name: str) -> None:
    edit, field, words = READ_CASES[name]
    p = _edited(tmp_path, plan_path, edit)
    with pytest.raises(PlanFileError) as err:
        read_plan(p)
    msg = str(err.value)
    assert msg.startswith(f"{p}: {field}") and "\n" not in msg and words in msg, msg


@pytest.mark.parametrize("key", ["joint_velocities", "joint_accelerations"])
def test_check_plan_refuses_rates_that_are_not_the_joints(plan_path: Path, tmp_path: Path, key: str) -> None:
    def edit(d: dict) -> None:
        d["samples"][key] = (0.5 * np.array(d["samples"][key])).tolist()

    p = _edited(tmp_path, plan_path, edit)
    with pytest.raises(PlanFileError) as err:
        check_plan(read_plan(p), str(p))
    assert str(err.value).startswith(f"{p}: samples.{key}[") and "derivative" in str(err.value), str(err.value)


# --- export formats ---------------------------------------------------------------------------------

@pytest.mark.parametrize("fmt", FORMATS)
def test_export_round_trip(plan: Plan, tmp_path: Path, fmt: str) -> None:
    out = export_plan(plan, tmp_path / f"traj{SUFFIXES[fmt]}", fmt)
    back = read_trajectory(out)
    assert back.joint_names == plan.joint_names
    atol = 5e-10 if fmt == "joint-trajectory" else 0.0  # the message's times are in nanoseconds
    np.testing.assert_allclose(back.t, plan.t, rtol=0, atol=atol)
    for got, want in ((back.positions, plan.joints), (back.velocities, plan.joint_velocities),
                      (back.accelerations, plan.joint_accelerations)):
        np.testing.assert_array_equal(got, want)
    assert back.phase == (() if fmt == "joint-trajectory" else plan.phase)


def test_export_names_the_joints_for_the_robot(plan: Plan, tmp_path: Path) -> None:
    names = ("waist", "shoulder", "elbow")
    for fmt in FORMATS:
        out = export_plan(plan, tmp_path / f"named{SUFFIXES[fmt]}", fmt, names)
        assert read_trajectory(out).joint_names == names
    head = (tmp_path / "named.csv").read_text().splitlines()[0]
    assert head == ("t,waist_position,shoulder_position,elbow_position,waist_velocity,shoulder_velocity,"
                    "elbow_velocity,waist_acceleration,shoulder_acceleration,elbow_acceleration,phase")


def test_the_joint_trajectory_is_shaped_like_the_ros_message(plan: Plan) -> None:
    msg = joint_trajectory_message(Trajectory.from_plan(plan))
    assert set(msg) == {"header", "joint_names", "points"}
    assert msg["header"] == {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""}
    assert len(msg["points"]) == plan.t.size
    for point in msg["points"]:
        assert set(point) == {"positions", "velocities", "accelerations", "effort", "time_from_start"}
        assert all(len(point[k]) == 3 for k in ("positions", "velocities", "accelerations"))
        d = point["time_from_start"]
        assert set(d) == {"sec", "nanosec"} and type(d["sec"]) is int and 0 <= d["nanosec"] < 10**9
    ns = [p["time_from_start"]["sec"] * 10**9 + p["time_from_start"]["nanosec"] for p in msg["points"]]
    assert np.all(np.diff(ns) > 0)
    json.dumps(msg, allow_nan=False)


def test_the_joint_trajectory_file_is_the_message_as_readable_json(plan: Plan) -> None:
    """The file's text (a template per point) is the message laid out by readable_json, byte for byte:
    the plan's, with other names, with non-finite and extreme numbers, and with no points."""
    from tooltransfer.readable_json import dumps

    inf, nan = float("inf"), float("nan")
    odd = np.array([[nan, inf, -inf], [1e-300, -0.0, 5e300], [1, 2, 3]])
    trajectories = [Trajectory.from_plan(plan), Trajectory.from_plan(plan, ('a"b', "\u00e9", "x\\y")),
                    Trajectory(np.array([0.0, 0.9999999999, 1e9]), odd, -odd, odd * 1e-7),
                    Trajectory(np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)))]
    for traj in trajectories:
        assert joint_trajectory_text(traj) == dumps(joint_trajectory_message(traj)) + "\n"


def test_a_time_just_below_a_second_carries_over() -> None:
    from tooltransfer.planner.execution.export import _duration

    assert _duration(0.9999999999) == {"sec": 1, "nanosec": 0}
    assert _duration(2.5) == {"sec": 2, "nanosec": 500_000_000}


# --- the command line -------------------------------------------------------------------------------

@pytest.mark.parametrize("fmt", FORMATS)
def test_export_command_writes_beside_the_plan(plan: Plan, plan_path: Path, tmp_path: Path, capsys,
                                               fmt: str) -> None:
    p = tmp_path / "plan.json"
    p.write_bytes(plan_path.read_bytes())
    assert main(["export", str(p), "--format", fmt]) == 0
    out = tmp_path / f"plan{SUFFIXES[fmt]}"
    assert f"wrote {out}" in capsys.readouterr().out
    np.testing.assert_array_equal(read_trajectory(out).velocities, plan.joint_velocities)


def test_export_command_options(plan_path: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "arm.json"
    assert main(["export", str(plan_path), "--format", "joint-trajectory", "-o", str(out),
                 "--joint-names", "waist,shoulder,elbow"]) == 0
    assert json.loads(out.read_text())["joint_names"] == ["waist", "shoulder", "elbow"]
    for bad in ("a,b", "a,a,b", "a,,c"):
        capsys.readouterr()
        assert main(["export", str(plan_path), "--format", "csv", "-o", str(tmp_path / "x.csv"),
                     "--joint-names", bad]) == 2
        err = capsys.readouterr().err
        assert err.startswith("tooltransfer: error: --joint-names: expected 3 distinct") and err.count("\n") == 1
    assert not (tmp_path / "x.csv").exists()
    assert main(["export", str(plan_path), "--format", "csv", "-o", str(plan_path)]) == 2
    assert "-o/--out: expected a file other than the plan" in capsys.readouterr().err
    assert json.loads(plan_path.read_text())["format"] == "tooltransfer.plan/1"


@pytest.mark.parametrize("content, words", [
    (None, "a readable plan file"),
    ("{not json", "valid JSON"),
    ('{"format": "tooltransfer.plan/9"}', "format"),
    ("[]", "format"),
])
def test_export_of_a_bad_plan_file_exits_2_naming_the_file(tmp_path: Path, capsys, content: str | None,
                                                           words: str) -> None:
    p = tmp_path / "bad.json"
    if content is not None:
        p.write_text(content)
    assert main(["export", str(p), "--format", "npz"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"tooltransfer: error: {p}: ") and words in err and err.count("\n") == 1, err
    assert sorted(x.name for x in tmp_path.iterdir()) == ([] if content is None else ["bad.json"])


def test_export_of_a_plan_that_lies_exits_2_unless_forced(plan_path: Path, tmp_path: Path, capsys) -> None:
    p = _edited(tmp_path, plan_path, lambda d: d["samples"].update(
        joint_velocities=np.zeros((len(d["samples"]["t"]), 3)).tolist()))
    out = tmp_path / "out.csv"
    assert main(["export", str(p), "--format", "csv", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"tooltransfer: error: {p}: samples.joint_velocities[") and not out.exists(), err
    assert main(["export", str(p), "--format", "csv", "-o", str(out), "--force"]) == 0
    assert "warning" in capsys.readouterr().err and out.exists()


def test_export_of_an_infeasible_or_violated_plan(plan_path: Path, tmp_path: Path, capsys) -> None:
    infeasible = Plan(status="infeasible", variant={"oe": "qp", "ss": "opt"}, task={"name": "x"}, platform={},
                      object={}, tool={}, obstacles=[], reason="no push sequence").write(tmp_path / "inf.json")
    assert main(["export", str(infeasible), "--format", "csv"]) == 1
    assert "infeasible: no push sequence" in capsys.readouterr().out
    assert not (tmp_path / "inf.csv").exists()

    def violate(d: dict) -> None:
        d.update(status="violated", reason="hard checks violated: cone")

    p = _edited(tmp_path, plan_path, violate)
    assert main(["export", str(p), "--format", "npz"]) == 1
    assert "--force" in capsys.readouterr().out
    assert main(["export", str(p), "--format", "npz", "--force"]) == 0
    assert "violated" in capsys.readouterr().err and (tmp_path / "edited.npz").exists()


def test_read_trajectory_names_the_file_of_a_bad_export(tmp_path: Path) -> None:
    from tooltransfer.errors import InputError

    cases = {"a.csv": "t,a\n1,2\n", "b.trajectory.json": '{"points": [{"positions": [1, 2, 3]}]}',
             "c.npz": "not a zip", "d.txt": "x"}
    for name, text in cases.items():
        p = tmp_path / name
        p.write_text(text)
        with pytest.raises(InputError) as err:
            read_trajectory(p)
        assert str(err.value).startswith(f"{p}: "), str(err.value)

