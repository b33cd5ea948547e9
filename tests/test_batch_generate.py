"""Batch files and task generation: deterministic, inside the asked ranges, every task a valid task
file that `tooltransfer solve` accepts on its own; broken batch files end in exit code 2 naming the field."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import shapely
import yaml

from tooltransfer.planner.apps.batch.generate import _reach, generate_tasks, write_tasks
from tooltransfer.planner.apps.batch.spec import batch_from_dict, load_batch
from tooltransfer.planner.apps.cli import main
from tooltransfer.problems.task import load_task

ROOT = Path(__file__).resolve().parents[1]
SMALL = ROOT / "problems" / "batch" / "small.yaml"


def _spec(tmp_path: Path, **changes) -> Path:
    data = yaml.safe_load(SMALL.read_text())
    data.update(changes)
    data["dataset"] = str(ROOT / "problems" / "data" / "finger_demos")
    p = tmp_path / "batch.yaml"
    p.write_text(yaml.safe_dump(data))
    return p


def test_generation_is_deterministic_and_task_i_does_not_depend_on_count(tmp_path) -> None:
    a = generate_tasks(load_batch(SMALL), SMALL)
    b = generate_tasks(load_batch(SMALL), SMALL)
    assert [t.data for t in a] == [t.data for t in b]
    longer = load_batch(_spec(tmp_path, count=12))
    c = generate_tasks(longer, _spec(tmp_path, count=12))
    assert [t.data["start"] for t in c[:8]] == [t.data["start"] for t in a]
    other = generate_tasks(load_batch(_spec(tmp_path, seed=8)), tmp_path / "batch.yaml")
    assert [t.data["start"] for t in other] != [t.data["start"] for t in a]


def test_generated_tasks_keep_the_asked_ranges(tmp_path) -> None:
    p = _spec(tmp_path, count=40, obstacles={"count": [1, 3], "radius": [0.003, 0.007], "kinds": ["disc", "polygon"],
                                             "clearance": 0.004})
    spec = load_batch(p)
    tasks = generate_tasks(spec, p)
    assert [t.tool for t in tasks[:4]] == ["slope", "finger", "slope", "finger"]
    kinds = set()
    for t in tasks:
        s, g = np.array(t.data["start"]), np.array(t.data["target"])
        d = np.linalg.norm(g - s)
        assert 0.04 - 1e-5 <= d <= 0.10 + 1e-5
        heading = math.atan2(*(g - s)[::-1])
        assert 1.9 - 1e-3 <= heading <= 3.1 + 1e-3
        assert t.start_reach >= 0.015 - 1e-5 and t.target_reach >= 0.005 - 1e-5
        reach = _reach(t.tool, "{}")
        assert reach.contains(shapely.Point(s)) and reach.contains(shapely.Point(g))
        assert 0 <= t.n_obstacles <= 3 and len(t.data["obstacles"]) == t.n_obstacles
        keep = 0.0175 + 0.005 + 0.004
        for o in t.data["obstacles"]:
            kinds.add(o["kind"])
            shape = (shapely.Point(o["centre"]).buffer(o["radius"], 64) if o["kind"] == "disc"
                     else shapely.Polygon(o["vertices"]))
            assert shape.distance(shapely.Point(s)) >= keep - 1e-5
            assert shape.distance(shapely.Point(g)) >= keep - 1e-5
    assert kinds == {"disc", "polygon"}
    assert sum(t.n_obstacles for t in tasks) > 40  # mostly placed (count drawn in 1..3)


def test_written_tasks_load_and_solve_on_their_own(tmp_path, capsys) -> None:
    out = tmp_path / "elsewhere" / "tasks"
    paths = write_tasks(load_batch(SMALL), SMALL, out)
    assert len(paths) == 8
    for p in paths:
        task = load_task(p)  # valid on its own, dataset relative to the file's folder
        assert (p.parent / task.skills.dataset).resolve() == (ROOT / "problems" / "data" / "finger_demos").resolve()
    for p, expected in ((paths[0], 0), (paths[2], 1)):  # seed 7's quick two: solved, certified infeasible
        code = main(["solve", str(p)])
        assert code == expected, capsys.readouterr()  # the verdict, not bad input (2)
    assert main(["batch", "generate", str(SMALL), "--out", str(tmp_path / "cli")]) == 0
    assert sorted(x.name for x in (tmp_path / "cli").iterdir()) == sorted(x.name for x in paths)
    for p in paths:  # the same tasks (the dataset path differs: relative to each folder)
        a, b = load_task(p).model_dump(), load_task(tmp_path / "cli" / p.name).model_dump()
        assert {**a, "skills": None} == {**b, "skills": None}


@pytest.mark.parametrize(("change", "field"), [
    ({"count": -1}, "count"),
    ({"count": "many"}, "count"),
    ({"tools": ["spoon"]}, "tools"),
    ({"distance": [0.1, 0.05]}, "distance"),
    ({"distance": [0.05, float("nan")]}, "distance[1]"),
    ({"obstacles": {"radius": [-0.01, 0.01]}}, "obstacles.radius[0]"),
    ({"obstacles": {"count": [0, 2], "kinds": ["cube"]}}, "obstacles.kinds[0]"),
    ({"start": {"reach_margin": float("inf")}}, "start.reach_margin"),
    ({"variants": {"oe": ["fast"]}}, "variants.oe[0]"),
    ({"task": {"start": [0, 0]}}, "task"),
    ({"dataset": "no/such/folder"}, "dataset"),
    ({"wrong_key": 1}, "wrong_key"),
    ({"start": {"reach_margin": 0.09}}, "batch (start, target"),
])
def test_broken_batch_files_exit_2_naming_the_field(tmp_path, capsys, change, field) -> None:
    data = yaml.safe_load(SMALL.read_text())
    data["dataset"] = str(ROOT / "problems" / "data" / "finger_demos")
    data.update(change)
    p = tmp_path / "bad.yaml"
    p.write_text(yaml.safe_dump(data))
    assert main(["batch", "generate", str(p), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("tooltransfer: error:") and field in err, err
    assert "Traceback" not in err


def test_batch_schema_and_unreadable_file(tmp_path, capsys) -> None:
    import json

    assert main(["batch", "schema"]) == 0
    assert "count" in json.loads(capsys.readouterr().out)["required"]
    bad = tmp_path / "b.yaml"
    bad.write_text("name: [unclosed\n")
    assert main(["batch", "run", str(bad), "--db", str(tmp_path / "r.sqlite")]) == 2
    assert "line 2" in capsys.readouterr().err
    assert batch_from_dict({"name": "x", "count": 1, "tools": ["slope"], "dataset": "."}).timeout == 60.0
