"""Hostile files met as data (real FIFOs, a sparse giant, links out of a dataset, kernel files): refused
by name at once, no hang, no memory blow-up, no quoted content of a file outside the user's text, no
path followed out of a dataset; a cache edited to other valid values is learned again."""

from __future__ import annotations

import json
import os
import shutil
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml

from tooltransfer.planner.apps.cli import main
from tooltransfer.problems.dataset import DatasetError, load_dataset

ROOT = Path(__file__).resolve().parents[1]
DATASET = ROOT / "problems" / "data" / "finger_demos"
SECRET = "TOKEN-7f3a-do-not-print"


def _within(seconds: float, fn: Callable[[], Any]) -> BaseException | Any:
    """``fn()`` in a thread, which must end within ``seconds`` (a hang fails the test, not the suite):
    its exception, or its value."""
    out: list = []

    def run() -> None:
        try:
            out.append(fn())
        except BaseException as exc:  # handed to the test
            out.append(exc)

    t = threading.Thread(target=run, daemon=True)
    start = time.monotonic()
    t.start()
    t.join(seconds)
    assert not t.is_alive(), f"still reading after {seconds} s"
    assert time.monotonic() - start < seconds
    return out[0]


@pytest.fixture
def ds(tmp_path: Path) -> Path:
    """A copy of the committed finger dataset, and a secret file beside it (outside it)."""
    shutil.copytree(DATASET, tmp_path / "ds")
    (tmp_path / "token").write_text(f"{SECRET}\nsecond line\n")
    return tmp_path / "ds"


def _meta(ds: Path, **change: Any) -> None:
    meta = yaml.safe_load((ds / "meta.yaml").read_text())
    meta.update(change)
    (ds / "meta.yaml").write_text(yaml.safe_dump(meta))


def _refused(ds: Path, *words: str) -> str:
    """``load_dataset(ds)`` raises at once a DatasetError naming ``words`` and quoting no secret."""
    err = _within(10, lambda: load_dataset(ds))
    assert isinstance(err, DatasetError), err
    text = str(err)
    for w in words:
        assert w in text, text
    assert SECRET not in text and "root:x:0" not in text and "second line" not in text, text
    return text


def _link_out(ds: Path, name: str, target: str) -> None:
    """Replace the dataset's ``name`` by a link to ``target`` outside it (``token``: the secret beside the
    dataset) and check that loading refuses it by name, quoting nothing of the target."""
    (ds / name).unlink()
    (ds / name).symlink_to(ds.parent / target if target == "token" else target)
    _refused(ds, name, "leads outside")


@pytest.mark.parametrize("target", ["token", "/etc/passwd"])
def test_a_meta_yaml_linking_out_of_the_dataset_is_refused_unquoted(ds: Path, target: str) -> None:
    _link_out(ds, "meta.yaml", target)


@pytest.mark.parametrize("tool", ["/etc/passwd", "../../../../etc/passwd", "../token"])
def test_meta_tool_paths_stay_inside_the_dataset(ds: Path, tool: str) -> None:
    _meta(ds, tool=tool)
    _refused(ds, "field tool", "inside the dataset")


def test_a_tool_file_linked_out_of_the_dataset_is_refused(ds: Path) -> None:
    (ds / "tool.yaml").symlink_to(ds.parent / "token")
    _meta(ds, tool="tool.yaml")
    _refused(ds, "field tool", "leads outside")


@pytest.mark.parametrize("target", ["token", "/dev/zero", "/proc/kmsg", "/proc/self/environ"])
def test_a_demonstration_linking_out_of_the_dataset_is_refused(ds: Path, target: str) -> None:
    _link_out(ds, "demo_03.csv", target)


@pytest.mark.parametrize("name", ["meta.yaml", "demo_02.csv", "truth.yaml"])
def test_a_fifo_is_refused_by_name_at_once(ds: Path, name: str) -> None:
    (ds / name).unlink()
    os.mkfifo(ds / name)  # no writer: opening it for reading would block forever
    _refused(ds, name, "FIFO")


def test_a_sparse_giant_is_refused_by_its_size_before_it_is_read(ds: Path) -> None:
    with open(ds / "demo_05.csv", "r+b") as fh:
        fh.truncate(8 * 2**30)  # 8 GB, no block on disk
    text = _refused(ds, "demo_05.csv", "at most 32 MB")
    assert "8 GB" in text


def test_the_dataset_hash_reads_only_the_dataset_and_refuses_hostile_files(ds: Path) -> None:
    from tooltransfer.planner.learning.skills import dataset_hash

    clean = dataset_hash(ds)
    os.mkfifo(ds / "stray.fifo")  # not a file of the dataset: neither read nor in the hash
    (ds / "notes.bin").write_bytes(b"\0" * 1000)
    assert _within(10, lambda: dataset_hash(ds)) == clean
    (ds / "demo_01.csv").unlink()
    os.mkfifo(ds / "demo_01.csv")
    err = _within(10, lambda: dataset_hash(ds))
    assert isinstance(err, DatasetError) and "demo_01.csv" in str(err) and "FIFO" in str(err)


@pytest.mark.parametrize("folder", ["/proc", "/dev", "/sys"])
def test_a_kernel_folder_as_the_dataset_is_refused_at_once(folder: str) -> None:
    from tooltransfer.planner.learning.skills import learn_skills

    err = _within(10, lambda: learn_skills(folder))
    assert isinstance(err, DatasetError) and "meta.yaml" in str(err), err


def test_kernel_files_and_devices_are_refused_by_the_reader() -> None:
    from tooltransfer.regular_file import read_regular

    def error(path: str, where: str, expected: str, got: object) -> ValueError:
        return ValueError(f"{path}: {expected}, got {got}")

    for path, why in (("/proc/kmsg", "kernel"), ("/proc/self/environ", "kernel"), ("/dev/zero", "character device"),
                      ("/dev/null", "character device")):
        err = _within(10, lambda p=path: read_regular(p, error, "file", 2**20))
        assert isinstance(err, ValueError) and why in str(err), (path, err)


def test_a_fifo_task_file_exits_2_at_once(tmp_path: Path, capsys) -> None:
    os.mkfifo(tmp_path / "task.yaml")
    code = _within(20, lambda: main(["solve", str(tmp_path / "task.yaml")]))
    assert code == 2 and "FIFO" in capsys.readouterr().err


def test_learn_from_a_hostile_dataset_exits_2_quoting_nothing(ds: Path, tmp_path: Path, capsys) -> None:
    (ds / "meta.yaml").unlink()
    (ds / "meta.yaml").symlink_to("/etc/passwd")
    assert main(["learn", str(ds), "-o", str(tmp_path / "s.json")]) == 2
    err = capsys.readouterr().err
    assert "meta.yaml" in err and "root:" not in err and "Traceback" not in err


def test_a_cache_edited_to_other_valid_values_is_learned_again(tmp_path: Path, monkeypatch) -> None:
    """The mechanics cache: mu edited by hand (still a valid file) is not used; the identification is
    learned again and the cache rewritten."""
    from tooltransfer.planner.learning import skills

    monkeypatch.setenv("TOOLTRANSFER_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(skills, "_MEMORY", {})
    first = skills.identification_from_dataset(DATASET)
    (path,) = (tmp_path / "cache").glob("mech*.json")
    doc = json.loads(path.read_text())
    doc["payload"]["identification"]["summary"]["mu"] = 0.9  # another valid friction coefficient
    path.write_text(json.dumps(doc))
    monkeypatch.setattr(skills, "_MEMORY", {})
    again = skills.identification_from_dataset(DATASET)
    assert again.mechanics.mu == first.mechanics.mu != 0.9
    from tooltransfer.planner.learning.cache_file import read_cache

    assert read_cache(path, skills.dataset_hash(DATASET)) is not None  # rewritten with its checksum


def test_a_cache_file_reads_only_for_its_source_unchanged(tmp_path: Path) -> None:
    from tooltransfer.planner.learning.cache_file import read_cache, write_cache

    payload = {"format": "x/1", "values": [0.1, 1e-300, float("nan")], "k": 0.5}
    path = write_cache(tmp_path / "c.json", payload, "a" * 64)
    got = read_cache(path, "a" * 64)
    assert got is not None and got["values"][:2] == [0.1, 1e-300] and got["k"] == 0.5
    assert read_cache(path, "b" * 64) is None  # another dataset's
    doc = json.loads(path.read_text())
    doc["payload"]["k"] = 0.6
    path.write_text(json.dumps(doc))
    assert read_cache(path, "a" * 64) is None  # edited
    path.write_text(json.dumps(payload))
    assert read_cache(path, "a" * 64) is None  # an older cache file without a checksum


@pytest.mark.parametrize("command", [["simulate", "{p}"], ["export", "{p}", "--format", "csv", "-o", "{out}"]])
def test_a_fifo_plan_file_exits_2_at_once(tmp_path: Path, capsys, command: list[str]) -> None:
    os.mkfifo(tmp_path / "plan.json")
    argv = [a.format(p=tmp_path / "plan.json", out=tmp_path / "traj.csv") for a in command]
    code = _within(20, lambda: main(argv))
    assert code == 2 and "FIFO" in capsys.readouterr().err


def test_a_fifo_trajectory_is_refused_at_once(tmp_path: Path) -> None:
    from tooltransfer.errors import InputError
    from tooltransfer.planner.execution.export import read_trajectory

    os.mkfifo(tmp_path / "traj.csv")
    err = _within(10, lambda: read_trajectory(tmp_path / "traj.csv"))
    assert isinstance(err, InputError) and "FIFO" in str(err)


def test_a_skills_file_that_is_another_json_is_not_echoed(tmp_path: Path) -> None:
    from tooltransfer.errors import SkillFileError
    from tooltransfer.planner.learning.skills import load_skills_file

    (tmp_path / "token.json").write_text(json.dumps({"format": SECRET, "token": SECRET}))
    with pytest.raises(SkillFileError) as err:
        load_skills_file(tmp_path / "token.json")
    assert SECRET not in str(err.value) and "token.json" in str(err.value)
