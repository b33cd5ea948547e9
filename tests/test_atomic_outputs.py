"""Figures, tables, generated tasks and datasets are written atomically (issue 16, class 3): a writer
that fails half-way leaves the old file (or none), never half of a new one."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")


def test_a_figure_that_fails_half_way_leaves_the_old_file(tmp_path: Path) -> None:
    import matplotlib.pyplot as plt

    from tooltransfer.planner.apps.plots.save import save_figure

    out = tmp_path / "fig.png"
    out.write_bytes(b"old figure")
    fig, _ = plt.subplots()

    def broken(path, **kwargs) -> None:  # writes part of the file, then the disk fills
        Path(path).write_bytes(b"\x89PNG half")
        raise OSError(28, "No space left on device")

    fig.savefig = broken  # type: ignore[method-assign]
    with pytest.raises(OSError, match="No space left"):
        save_figure(fig, out)
    assert out.read_bytes() == b"old figure"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig.png"]  # no temporary left


def test_a_table_that_fails_half_way_is_not_written(tmp_path: Path) -> None:
    from tooltransfer.planner.apps.batch.report import write_csv

    class Bad:
        def __str__(self) -> str:
            raise RuntimeError("unprintable")

    out = tmp_path / "t.csv"
    with pytest.raises(RuntimeError):
        write_csv(out, [{"a": 1}, {"a": Bad()}])
    assert not out.exists() and list(tmp_path.iterdir()) == []
    assert write_csv(out, [{"a": 1}, {"a": 2}]).read_bytes() == b"a\r\n1\r\n2\r\n"


def test_a_dataset_writer_stopped_half_way_leaves_no_meta(tmp_path: Path, monkeypatch) -> None:
    from tooltransfer.problems import FINGER_DEMOS, dataset

    ds = dataset.load_dataset(FINGER_DEMOS)
    demos = list(ds.demonstrations)
    calls = []

    def stop_on_second(path, demo) -> None:
        calls.append(path)
        if len(calls) == 2:
            raise KeyboardInterrupt
        original(path, demo)

    original = dataset.write_demonstration
    monkeypatch.setattr(dataset, "write_demonstration", stop_on_second)
    with pytest.raises(KeyboardInterrupt):
        dataset.write_dataset(tmp_path / "ds", ds.meta, demos, ds.truth)
    assert not (tmp_path / "ds" / "meta.yaml").exists()  # nothing claims to be a complete dataset
    monkeypatch.setattr(dataset, "write_demonstration", original)
    again = dataset.load_dataset(dataset.write_dataset(tmp_path / "ds", ds.meta, demos, ds.truth))
    assert len(again.demonstrations) == len(demos)
