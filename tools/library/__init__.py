"""Tool files (this directory holds the library): YAML in SI units, loaded by name or path.

Format (one tool per file; lengths in metres, angles in radians, either a number or a multiple of
pi written as ``pi/2``, ``0.75*pi``, ``-pi/6``)::

    name: finger
    a_t: 0.026                       # [m] DH tool row length
    description: one line
    notes: where every number comes from
    outline: [[x, y], ...]           # [m] tool frame, simple polygon, either orientation
    faces:
      - name: upper
        segment: [[x0, y0], [x1, y1]]  # on one straight edge of the outline
        push_angle: pi/2             # [rad] direction the object moves, tool frame
        theta_b: pi/6                # [rad] cone half-angle, in (0, pi/2)
        contact_range: [0.0, 1.0]    # optional, fractions along the segment

``faces`` may be left out: the tool then gets the faces derived from its outline
(:mod:`tooltransfer.tools.derive`: every edge the object can touch, named ``edge_<i>``, with the full
friction cone about its normal) for the object radius and friction it is loaded for (by default the
paper's 17.5 mm puck and mu = 0.8).

Errors name the tool and the field path, e.g. ``faces[1].theta_b``.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

import shapely
import yaml

from tooltransfer.tools.errors import ToolSpecError, UnknownToolError
from tooltransfer.tools.model import Face, Tool

if TYPE_CHECKING:
    from tooltransfer.tools.omni.platform import OmniPlatform

_PI_EXPR = re.compile(r"^\s*([+-]?(?:\d+\.?\d*|\.\d+)?)\s*\*?\s*pi\s*(?:/\s*(\d+\.?\d*))?\s*$")
_TOOL_KEYS = {"name", "a_t", "description", "notes", "outline", "faces"}
_FACE_KEYS = {"name", "segment", "push_angle", "theta_b", "contact_range"}


def parse_angle(value: object, tool: str, field: str) -> float:
    """A number, or a multiple of pi such as ``"3*pi/4"``, as radians."""
    if isinstance(value, bool):
        raise ToolSpecError(tool, field, f"an angle [rad] is required, got {value!r}")
    if isinstance(value, int | float):
        return float(value)
    if isinstance(value, str):
        m = _PI_EXPR.match(value)
        if m:
            coef = m.group(1)
            k = 1.0 if coef in ("", "+") else -1.0 if coef == "-" else float(coef)
            den = float(m.group(2)) if m.group(2) else 1.0
            if den != 0.0:
                return k * 3.141592653589793 / den
    raise ToolSpecError(
        tool, field, f"an angle [rad] (number or k*pi/m) is required, got {value!r}"
    )


def _number(value: object, tool: str, field: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ToolSpecError(tool, field, f"a number is required, got {value!r}")
    return float(value)


def _points(
    value: object, tool: str, field: str, count: int | None = None
) -> list[tuple[float, float]]:
    if not isinstance(value, list) or (count is not None and len(value) != count):
        want = f"{count} points" if count else "a list of points"
        raise ToolSpecError(tool, field, f"{want} [x, y] is required")
    pts = []
    for k, p in enumerate(value):
        if not isinstance(p, list) or len(p) != 2:
            raise ToolSpecError(tool, f"{field}[{k}]", f"a point [x, y] is required, got {p!r}")
        pts.append(
            (_number(p[0], tool, f"{field}[{k}][0]"), _number(p[1], tool, f"{field}[{k}][1]"))
        )
    return pts


def _require(data: dict[str, Any], key: str, tool: str, prefix: str = "") -> Any:
    if key not in data:
        raise ToolSpecError(tool, f"{prefix}{key}", "missing required field")
    return data[key]


#: Most outline vertices of a tool file (the library's tools have 4-12; the convex decomposition and
#: every contact and clearance check scale with them).
MAX_VERTICES = 256
#: Most faces of a tool file (the push-sequence search grows with faces ** max_pushes).
MAX_FACES = 12


def tool_from_dict(data: object, source: str = "<dict>", *, object_radius: float | None = None,
                   friction: float | None = None,
                   platform: Callable[[float], OmniPlatform] | None = None) -> Tool:
    """Build and validate a :class:`Tool` from parsed YAML; ``source`` names it in errors. Without
    ``faces`` the faces are derived from the outline for a disc of ``object_radius`` [m], tool-object
    friction ``friction`` and the Omni ``platform(a_t)`` carrying it (defaults of
    :func:`tooltransfer.tools.derive.tool.derived_tool`); with ``faces`` these are not used."""
    if not isinstance(data, dict):
        raise ToolSpecError(source, "<root>", "a mapping with the tool's fields is required")
    name = data.get("name")
    tool = name if isinstance(name, str) and name else source
    for key in data:
        if key not in _TOOL_KEYS:
            raise ToolSpecError(
                tool, str(key), f"unknown field (known: {', '.join(sorted(_TOOL_KEYS))})"
            )
    name = _require(data, "name", tool)
    if not isinstance(name, str) or not name:
        raise ToolSpecError(tool, "name", "a non-empty string is required")
    a_t = _number(_require(data, "a_t", tool), tool, "a_t")
    raw_outline = _require(data, "outline", tool)
    if isinstance(raw_outline, list) and len(raw_outline) > MAX_VERTICES:
        raise ToolSpecError(tool, "outline", f"at most {MAX_VERTICES} vertices, got {len(raw_outline)}")
    outline = _points(raw_outline, tool, "outline")
    if len(outline) < 3:
        raise ToolSpecError(tool, "outline", "at least 3 vertices are required")
    if "faces" not in data:
        from tooltransfer.tools.derive.tool import derived_tool

        for key in ("description", "notes"):
            if not isinstance(data.get(key, ""), str):
                raise ToolSpecError(tool, key, "a string is required")
        return derived_tool(name, shapely.Polygon(outline), a_t, description=data.get("description", ""),
                            notes=data.get("notes", ""), object_radius=object_radius, friction=friction,
                            platform=None if platform is None else platform(a_t))
    raw_faces = data["faces"]
    if not isinstance(raw_faces, list) or not raw_faces:
        raise ToolSpecError(tool, "faces", "a non-empty list of faces is required")
    if len(raw_faces) > MAX_FACES:
        raise ToolSpecError(tool, "faces", f"at most {MAX_FACES} faces, got {len(raw_faces)}")
    faces = []
    for i, fd in enumerate(raw_faces):
        where = f"faces[{i}]"
        if not isinstance(fd, dict):
            raise ToolSpecError(tool, where, "a mapping is required")
        for key in fd:
            if key not in _FACE_KEYS:
                raise ToolSpecError(
                    tool,
                    f"{where}.{key}",
                    f"unknown field (known: {', '.join(sorted(_FACE_KEYS))})",
                )
        seg = _points(_require(fd, "segment", tool, f"{where}."), tool, f"{where}.segment", 2)
        cr = fd.get("contact_range", [0.0, 1.0])
        if not isinstance(cr, list) or len(cr) != 2:
            raise ToolSpecError(
                tool, f"{where}.contact_range", "two fractions [s0, s1] are required"
            )
        faces.append(
            Face(
                name=_require(fd, "name", tool, f"{where}."),
                start=seg[0],  # type: ignore[arg-type]
                end=seg[1],  # type: ignore[arg-type]
                push_angle=parse_angle(
                    _require(fd, "push_angle", tool, f"{where}."), tool, f"{where}.push_angle"
                ),
                theta_b=parse_angle(
                    _require(fd, "theta_b", tool, f"{where}."), tool, f"{where}.theta_b"
                ),
                contact_range=(
                    _number(cr[0], tool, f"{where}.contact_range[0]"),
                    _number(cr[1], tool, f"{where}.contact_range[1]"),
                ),
            )
        )
    for key in ("description", "notes"):
        if not isinstance(data.get(key, ""), str):
            raise ToolSpecError(tool, key, "a string is required")
    return Tool(
        name=name,
        outline=shapely.Polygon(outline),
        faces=tuple(faces),
        a_t=a_t,
        description=data.get("description", ""),
        notes=data.get("notes", ""),
    )


def tool_to_dict(tool: Tool) -> dict[str, Any]:
    """Plain-data form of ``tool`` (floats, lists, strings); inverse of :func:`tool_from_dict`."""
    ring = list(tool.outline.exterior.coords)[:-1]
    return {
        "name": tool.name,
        "a_t": tool.a_t,
        "description": tool.description,
        "notes": tool.notes,
        "outline": [[float(x), float(y)] for x, y in ring],
        "faces": [
            {
                "name": f.name,
                "segment": [[float(v) for v in f.start], [float(v) for v in f.end]],
                "push_angle": f.push_angle,
                "theta_b": f.theta_b,
                "contact_range": [f.contact_range[0], f.contact_range[1]],
            }
            for f in tool.faces
        ],
    }


def dump_tool(tool: Tool, path: str | Path | None = None) -> str:
    """YAML text of ``tool`` (exact float round trip); also written to ``path`` when given."""
    text = yaml.safe_dump(tool_to_dict(tool), sort_keys=False, default_flow_style=None, width=100)
    if path is not None:
        Path(path).write_text(text, encoding="utf-8")
    return text


def _library_dir() -> Path:
    return Path(__file__).resolve().parent


def library_names() -> tuple[str, ...]:
    """Names of the tools shipped in ``tools/library/``, sorted."""
    return tuple(sorted(p.stem for p in _library_dir().glob("*.yaml")))


def read_tool_file(path: str | Path, **derive: Any) -> Tool:
    """Load and validate one tool file (``derive``: the keyword arguments of :func:`tool_from_dict`
    for a file without faces)."""
    from tooltransfer.yaml_file import read_yaml

    p = Path(path)

    def error(source: str, where: str, expected: str, got: object) -> ToolSpecError:
        return ToolSpecError(source, where, expected if got is None else f"{expected}, got {got}")

    return tool_from_dict(read_yaml(p, error, "tool file"), source=str(p), **derive)


def load_tool(name_or_path: str | Path, **derive: Any) -> Tool:
    """A library tool by name (``"finger"``) or a tool file by path (``derive``: the keyword arguments
    of :func:`tool_from_dict` for a file without faces).

    Raises:
        UnknownToolError: ``name_or_path`` is neither a library name nor an existing file.
        ToolSpecError: the file is invalid (naming the field).
    """
    text = str(name_or_path)
    candidate = _library_dir() / f"{text}.yaml"
    if "/" not in text and "\\" not in text and candidate.is_file():
        return read_tool_file(candidate, **derive)
    p = Path(name_or_path)
    if (
        isinstance(name_or_path, Path)
        or p.suffix in (".yaml", ".yml")
        or p.is_file()
        or "/" in text
    ):
        return read_tool_file(p, **derive)
    raise UnknownToolError(text, library_names())


@cache
def library_has_faces(name: str) -> bool:
    """Whether the library tool ``name`` names its faces (False: they are derived from its outline)."""
    from tooltransfer.yaml_file import read_yaml

    def error(source: str, where: str, expected: str, got: object) -> ToolSpecError:
        return ToolSpecError(source, where, expected if got is None else f"{expected}, got {got}")

    data = read_yaml(_library_dir() / f"{name}.yaml", error, "tool file")
    return isinstance(data, dict) and "faces" in data


def load_library() -> dict[str, Tool]:
    """Every library tool, by name."""
    return {n: load_tool(n) for n in library_names()}
