"""Hostile input, class 2 of issue 16 (bytes and text): task files, dataset ``meta.yaml`` and
``truth.yaml``, batch files, CSVs and tool files in other encodings or binary, deeply nested YAML,
duplicate keys, alias-expansion bombs, huge values echoed, YAML 1.2 floats.

Every refused case ends in exit 2 with one short line naming the file (and the line, key or field
where there is one), within seconds, never a ``UnicodeDecodeError`` or ``RecursionError``. The
fixture files are in ``tests/hostile/text/`` (see its README); the hypothesis strategies below
are derandomized.
"""

from __future__ import annotations

import shutil
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.cli import main
from tooltransfer.yaml_file import MAX_ALIAS_EXPANSION, MAX_DEPTH, parse_yaml, read_yaml

HERE = Path(__file__).parent
FIXTURES = HERE / "hostile" / "text"
DATA = HERE.parent / "problems" / "data" / "finger_demos"
BATCH = HERE.parent / "problems" / "batch" / "small.yaml"
SETTINGS = settings(derandomize=True, deadline=None, max_examples=60,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])

#: words each fixture's message must hold (besides the file)
WORDS = {
    "utf16_bom": "UTF-16", "utf16le_no_bom": "UTF-16", "utf32": "UTF-32", "latin1": "not UTF-8",
    "binary.bin": "binary file", "nul_byte": "control characters", "nested_flow_5000": "nested",
    "nested_map_5000": "nested", "nested_block_80": "nested", "duplicate_start": "'start' is given again",
    "duplicate_nested": "'oe' is given again", "alias_bomb_description": "alias", "alias_bomb_start": "alias",
    "recursive_alias": "recursive",
}


class FileError(InputError):
    def __init__(self, path: str, where: str, expected: str, got: object | None = None) -> None:
        super().__init__(f"{path}: {where}", expected, got)


def cli(argv: list[str], capsys: pytest.CaptureFixture[str], seconds: float = 10.0) -> tuple[int, str]:
    """Run the command line; it must end within ``seconds`` with at most one short line on stderr."""
    capsys.readouterr()
    start = time.perf_counter()
    code = main(argv)
    took = time.perf_counter() - start
    err = capsys.readouterr().err
    assert took < seconds, (argv, took)
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) <= 1 and len(err) < 500, err[:1000]
    return code, err


def test_the_fixture_files_are_all_checked() -> None:
    assert {p.name.removesuffix(".yaml") for p in FIXTURES.glob("*.yaml")} == set(WORDS)


@pytest.mark.parametrize("path", sorted(FIXTURES.glob("*.yaml")), ids=lambda p: p.stem)
def test_hostile_task_files_are_refused_naming_the_file(path: Path, capsys) -> None:
    code, err = cli(["solve", str(path), "--json"], capsys)
    assert code == 2
    assert str(path) in err and WORDS[path.name.removesuffix(".yaml")] in err, err
    if "duplicate" in path.name or "nested" in path.name or "nul" in path.name:
        assert "line " in err  # where in the file


@pytest.mark.parametrize("path", sorted((FIXTURES / "accepted").glob("*.yaml")), ids=lambda p: p.stem)
def test_benign_variants_load(path: Path) -> None:
    from tooltransfer.problems.task import load_task

    task = load_task(path)
    assert task.safety_margin == 0.005 and task.start == (0.045, 0.12)
    assert task.obstacles[0].radius == 0.005


@pytest.mark.parametrize("case", ["unclosed", "value", "key", "oversized"])
def test_large_inputs_are_refused_quickly_and_not_echoed(tmp_path: Path, case: str, capsys) -> None:
    good = (FIXTURES / "accepted" / "utf8_bom.yaml").read_bytes()[3:].decode()
    text = {
        "unclosed": "name: x\nstart: " + "[" * 100_000 + "\n",
        "value": good.replace("start: [0.045, 0.12]", "start: '" + "y" * 200_000 + "'"),
        "key": good + "z" * 200_000 + ": 1\n",
        "oversized": good + "# " + "z" * 3_000_000 + "\n",
    }[case]
    p = tmp_path / "task.yaml"
    p.write_text(text)
    code, err = cli(["solve", str(p)], capsys)
    assert code == 2 and str(p) in err
    assert {"unclosed": "nested", "value": "start", "key": "line 12", "oversized": "at most 1 MB"}[case] in err


def _meta_folder(tmp_path: Path) -> Path:
    folder = tmp_path / "ds"
    folder.mkdir()
    shutil.copy(DATA / "meta.yaml", folder / "meta.yaml")
    return folder


@pytest.mark.parametrize("case", ["utf-16", "latin-1", "duplicate", "bomb", "nested"])
def test_hostile_meta_yaml_is_refused_naming_it(tmp_path: Path, case: str) -> None:
    from tooltransfer.problems.dataset import DatasetError, load_meta

    folder = _meta_folder(tmp_path)
    meta = folder / "meta.yaml"
    text = meta.read_text()
    laughs = "".join(f"  l{i}: &l{i} [" + ", ".join([f"*l{i - 1}"] * 10 if i else ["x"] * 10) + "]\n" for i in range(7))
    data = {
        "utf-16": text.encode("utf-16"),
        "latin-1": text.replace("frame: '", "frame: 'caf\xe9 ").encode("latin-1"),
        "duplicate": (text + "tool: slope\n").encode(),
        "bomb": text.replace("scene:\n", "scene:\n" + laughs).encode(),
        "nested": text.replace("scene:\n", "scene:\n  deep: " + "[" * 3000 + "]" * 3000 + "\n").encode(),
    }[case]
    meta.write_bytes(data)
    with pytest.raises(DatasetError) as exc:
        load_meta(folder)
    msg = str(exc.value)
    assert str(meta) in msg and len(msg) < 300
    assert {"utf-16": "UTF-16", "latin-1": "not UTF-8", "duplicate": "'tool' is given again", "bomb": "alias",
            "nested": "nested"}[case] in msg


def test_meta_yaml_takes_exponent_floats(tmp_path: Path) -> None:
    from tooltransfer.problems.dataset import load_meta

    folder = _meta_folder(tmp_path)
    meta = folder / "meta.yaml"
    meta.write_text(meta.read_text().replace("object_radius: 0.0175", "object_radius: 1.75e-2"))
    assert load_meta(folder).object_radius == pytest.approx(0.0175)


@pytest.mark.parametrize("case", ["truth utf-16", "truth syntax", "csv utf-16", "tool utf-16"])
def test_hostile_dataset_files_exit_2_naming_the_file(tmp_path: Path, case: str, capsys) -> None:
    folder = tmp_path / "ds"
    shutil.copytree(DATA, folder)
    if case == "truth utf-16":
        target = folder / "truth.yaml"
        target.write_bytes(target.read_text().encode("utf-16"))
    elif case == "truth syntax":
        target = folder / "truth.yaml"
        target.write_text(target.read_text() + "\n  - [unclosed\n")
    elif case == "csv utf-16":
        target = folder / "demo_00.csv"
        target.write_bytes(target.read_text().encode("utf-16"))
    else:  # the dataset's tool as a tool file of its own, in UTF-16
        target = folder / "mytool.yaml"
        target.write_bytes((HERE.parent / "tools" / "library" / "finger.yaml").read_text().encode("utf-16"))
        meta = folder / "meta.yaml"
        meta.write_text(meta.read_text().replace("tool: finger", "tool: mytool.yaml"))
    code, err = cli(["segment", str(folder)], capsys)
    assert code == 2 and target.name in err, err


@pytest.mark.parametrize("case", ["duplicate", "bomb", "utf-16", "exponent"])
def test_hostile_batch_files(tmp_path: Path, case: str) -> None:
    from tooltransfer.planner.apps.batch.spec import BatchFileError, load_batch

    text = BATCH.read_text().replace("../data/finger_demos", str(DATA))
    laughs = "".join(f"  l{i}: &l{i} [" + ", ".join([f"*l{i - 1}"] * 10 if i else ["x"] * 10) + "]\n" for i in range(6))
    p = tmp_path / "batch.yaml"
    data = {
        "duplicate": (text + "count: 3\n").encode(),
        "bomb": text.replace("task: {", "task: {description: *l5, ").replace("format:", "zz:\n" + laughs + "format:")
        .encode(),
        "utf-16": text.encode("utf-16"),
        "exponent": text.replace("distance: [0.04, 0.10]", "distance: [4e-2, 1E-1]").encode(),
    }[case]
    p.write_bytes(data)
    if case == "exponent":
        assert load_batch(p).distance == (0.04, 0.1)
        return
    with pytest.raises(BatchFileError) as exc:
        load_batch(p)
    msg = str(exc.value)
    assert str(p) in msg and len(msg) < 300
    assert {"duplicate": "'count' is given again", "bomb": "alias", "utf-16": "UTF-16"}[case] in msg


# --- hypothesis strategies -------------------------------------------------------------------------

EXPONENT_FLOATS = st.builds(
    lambda sign, whole, frac, e, esign, exp: f"{sign}{whole}{frac}{e}{esign}{exp}",
    st.sampled_from(["", "-", "+"]), st.integers(0, 999).map(str),
    st.sampled_from(["", ".", ".5", ".25", ".125"]), st.sampled_from(["e", "E"]),
    st.sampled_from(["", "-", "+"]), st.integers(0, 30).map(str),
)


@SETTINGS
@given(EXPONENT_FLOATS)
def test_exponent_floats_are_numbers(text: str) -> None:
    value = parse_yaml(f"v: {text}\nq: '{text}'\n", "f.yaml", FileError)
    assert isinstance(value["v"], float) and value["v"] == float(text)
    assert value["q"] == text  # quoted text stays text


@SETTINGS
@given(st.integers(-10**12, 10**12))
def test_integers_stay_integers(n: int) -> None:
    assert parse_yaml(f"v: {n}\n", "f.yaml", FileError) == {"v": n}


KEYS = st.lists(st.from_regex(r"[a-z_][a-z0-9_]{0,8}", fullmatch=True), min_size=2, max_size=12, unique=True)


@SETTINGS
@given(KEYS, st.data(), st.booleans())
def test_a_key_given_twice_is_named_with_its_lines(keys: list[str], data: st.DataObject, nested: bool) -> None:
    first = data.draw(st.integers(0, len(keys) - 1))
    again = data.draw(st.integers(first + 1, len(keys)))
    order = [*keys[:again], keys[first], *keys[again:]]
    indent = "  " if nested else ""
    text = ("outer:\n" if nested else "") + "".join(f"{indent}{k}: {i}\n" for i, k in enumerate(order))
    with pytest.raises(FileError) as exc:
        parse_yaml(text, "f.yaml", FileError)
    msg, off = str(exc.value), int(nested)
    assert f"'{keys[first]}' is given again" in msg
    assert f"line {again + 1 + off}," in msg and f"first on line {first + 1 + off}" in msg


@SETTINGS
@given(st.integers(1, 4000), st.sampled_from(["[", "{a: ", "- "]))
def test_nesting_is_bounded_without_recursion_errors(depth: int, opener: str) -> None:
    if opener == "[":
        text = "[" * depth + "]" * depth
    elif opener == "{a: ":
        text = "{a: " * depth + "1" + "}" * depth
    else:  # block sequences, one more space each level (libyaml stops at 1000 levels)
        depth = min(depth, 1200)
        text = "".join(" " * i + "-\n" for i in range(depth - 1)) + " " * (depth - 1) + "- 1\n"
    if depth <= MAX_DEPTH:
        node = parse_yaml(text, "f.yaml", FileError)
        for _ in range(depth - 1):
            node = node[0] if isinstance(node, list) else node["a"]
        assert node in ([], [1], {"a": 1})
        return
    with pytest.raises(FileError, match="nested collections"):
        parse_yaml(text, "f.yaml", FileError)


@SETTINGS
@given(st.integers(2, 12), st.integers(1, 8))
def test_alias_expansion_is_bounded(width: int, levels: int) -> None:
    lines = [f"l0: &l0 [{', '.join(['x'] * width)}]"]
    lines += [f"l{i}: &l{i} [{', '.join([f'*l{i - 1}'] * width)}]" for i in range(1, levels)]
    expanded, size = 0, 1 + width
    for _ in range(levels):
        expanded += size
        size = 1 + width * size
    written = (1 + width) + (levels - 1)
    added = expanded - written
    if added <= MAX_ALIAS_EXPANSION:
        doc = parse_yaml("\n".join(lines), "f.yaml", FileError)
        assert len(doc) == levels and doc["l0"] == ["x"] * width
        return
    with pytest.raises(FileError) as exc:
        parse_yaml("\n".join(lines), "f.yaml", FileError)
    assert "alias" in str(exc.value) and len(str(exc.value)) < 200


@SETTINGS
@given(st.sampled_from(["utf-16", "utf-16-le", "utf-16-be", "utf-32", "latin-1", "cp1252"]),
       st.text(alphabet="abcdéèüß: -\n", min_size=1, max_size=200))
def test_other_encodings_are_named_not_decode_errors(tmp_path_factory, encoding: str, body: str) -> None:
    p = tmp_path_factory.mktemp("enc") / "file.yaml"
    p.write_bytes(("name: é\n" + body).encode(encoding))
    with pytest.raises(FileError) as exc:
        read_yaml(p, FileError, "task file")
    assert str(p) in str(exc.value) and "UTF-8" in str(exc.value)


@SETTINGS
@given(st.binary(min_size=1, max_size=3000))
def test_arbitrary_bytes_give_a_value_or_the_error(tmp_path_factory, data: bytes) -> None:
    p = tmp_path_factory.mktemp("bytes") / "file.yaml"
    p.write_bytes(data)
    try:
        read_yaml(p, FileError, "task file")
    except FileError as exc:
        assert str(exc).startswith(str(p)) and len(str(exc)) < 400


@SETTINGS
@given(st.text(min_size=150, max_size=20_000))
def test_long_values_are_cut_in_messages(value: str) -> None:
    from tooltransfer.problems.task import TaskFileError, task_from_dict

    base = yaml.safe_load((FIXTURES / "accepted" / "utf8_bom.yaml").read_bytes()[3:])
    for field in ("start", "tool", "name"):
        with pytest.raises(TaskFileError) as exc:
            task_from_dict({**base, field: value * 2 if field != "tool" else value}, "t.yaml")
        assert len(str(exc.value)) < 400 and "\n" not in str(exc.value)


def test_tool_files_are_read_by_the_safe_reader(tmp_path: Path) -> None:
    """A tool file in UTF-16, with a key twice, or with 10,000 outline vertices is refused naming
    the file and the place (tool files used to be read with a bare yaml.safe_load)."""
    from tooltransfer.tools.errors import ToolSpecError
    from tooltransfer.tools.library import read_tool_file

    slope = Path(__file__).resolve().parents[1] / "tools" / "library" / "slope.yaml"
    u16 = tmp_path / "u16.yaml"
    u16.write_bytes(slope.read_text().encode("utf-16"))
    dup = tmp_path / "dup.yaml"
    dup.write_text("name: a\nname: b\n")
    big = tmp_path / "big.yaml"
    ring = [[0.01 * float(np.cos(a)), 0.01 * float(np.sin(a))] for a in np.linspace(0, 6.28, 10_000, endpoint=False)]
    big.write_text(yaml.safe_dump({"name": "big", "a_t": 0.03, "outline": ring,
                                   "faces": [{"name": "f", "segment": [ring[0], ring[1]], "push_angle": 0.0,
                                              "theta_b": 0.5}]}))
    for path, words in ((u16, "UTF-16"), (dup, "given again"), (big, "at most 256 vertices")):
        with pytest.raises(ToolSpecError, match=words) as err:
            read_tool_file(path)
        assert str(path) in str(err.value) or "big" in str(err.value)
