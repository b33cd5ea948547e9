"""The readable JSON writer: the same value as json.dumps, objects indented, numeric arrays on one line."""

import json
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tooltransfer.readable_json import dumps

_scalars = st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=5)
_values = st.recursive(_scalars, lambda inner: st.lists(inner, max_size=4)
                       | st.dictionaries(st.text(max_size=4), inner, max_size=4), max_leaves=30)


@settings(max_examples=300, derandomize=True, deadline=None)
@given(_values)
def test_parses_to_what_json_dumps_gives(value: object) -> None:
    assert json.loads(dumps(value)) == json.loads(json.dumps(value))


def test_layout_objects_indented_number_arrays_on_one_line() -> None:
    doc = {"format": "x/1", "samples": {"t": [0.0, 0.5, 1.0], "pose": [[1, 2, 3], [4, 5, 6]]},
           "pushes": [{"faces": ["a"]}], "empty": {}}
    assert dumps(doc, indent=2).splitlines() == [
        "{",
        '  "format": "x/1",',
        '  "samples": {',
        '    "t": [0.0, 0.5, 1.0],',
        '    "pose": [[1, 2, 3], [4, 5, 6]]',
        "  },",
        '  "pushes": [',
        "    {",
        '      "faces": ["a"]',
        "    }",
        "  ],",
        '  "empty": {}',
        "}",
    ]


def test_non_string_keys_and_non_finite_numbers_as_json_dumps() -> None:
    doc = {1: math.inf, None: [math.nan]}
    assert dumps(doc).replace("\n", "").replace(" ", "") == json.dumps(doc).replace(" ", "")
    with pytest.raises(ValueError):
        dumps(doc, allow_nan=False)


def test_arrays_of_objects_and_circular_references_as_json_dumps() -> None:
    """An array whose first item is an object is laid out without being encoded whole first; the text
    is the same, and a document that holds itself is refused as json.dumps refuses it."""
    points = [{"p": [0.1, 2.0], "t": {"sec": k, "nanosec": 5}} for k in range(3)]
    doc = {"points": points, "mixed": [1, {"a": []}], "strings": ["{", {}]}
    assert json.loads(dumps(doc)) == doc
    assert dumps({"points": points[:1]}).splitlines() == [
        "{", ' "points": [', "  {", '   "p": [0.1, 2.0],', '   "t": {', '    "sec": 0,', '    "nanosec": 5',
        "   }", "  }", " ]", "}"]
    loop: list[object] = [{}]
    loop.append(loop)
    for bad in (loop, {"x": loop}):
        with pytest.raises(ValueError, match="Circular reference"):
            json.dumps(bad)
        with pytest.raises(ValueError, match="Circular reference"):
            dumps(bad)
