"""A tool outline from what a user has: points, an SVG path, an SVG file, or a tool file.

:func:`outline_from` returns a shapely polygon in the tool frame [m]. SVG input (a path's ``d``
string, or the first ``<path>`` of an ``.svg`` file) is in ``svg_scale`` metres per unit
(default millimetres) with its y axis flipped (SVG's points down); its curves and arcs become
chords within ``arc_tolerance`` [m] of them (:mod:`tooltransfer.tools.derive.svg_path`).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import shapely

from tooltransfer.errors import InputError
from tooltransfer.tools.derive.defaults import ARC_TOLERANCE, SVG_SCALE  # the defaults, under their names here too
from tooltransfer.tools.derive.svg_path import flatten_path

_PATH_START = re.compile(r"^\s*[Mm]")


def svg_polygon(d: str, *, arc_tolerance: float = ARC_TOLERANCE, svg_scale: float = SVG_SCALE) -> shapely.Polygon:
    """The polygon [m] of SVG path data ``d`` (units of ``svg_scale`` m, y flipped)."""
    for name, v in (("arc_tolerance", arc_tolerance), ("svg_scale", svg_scale)):
        if not isinstance(v, int | float) or not np.isfinite(v) or v <= 0:
            raise InputError(name, "a positive number", repr(v))
    ring = flatten_path(d, arc_tolerance / svg_scale) * np.array([svg_scale, -svg_scale])
    return _checked(ring.tolist(), "outline")


def _checked(points: Any, where: str) -> shapely.Polygon:
    try:
        ring = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(where, "a list of points [x, y] [m]", repr(points)[:100]) from exc
    if ring.ndim != 2 or ring.shape[1] != 2 or len(ring) < 3 or not np.all(np.isfinite(ring)):
        raise InputError(where, "at least 3 finite points [x, y] [m]", repr(points)[:100])
    poly = shapely.Polygon(ring)
    if not poly.is_valid or poly.area <= 0:
        raise InputError(where, "a simple polygon with positive area", shapely.is_valid_reason(poly))
    return poly


def _svg_file(path: Path, arc_tolerance: float, svg_scale: float) -> shapely.Polygon:
    import xml.etree.ElementTree as ET

    try:
        root = ET.fromstring(path.read_text(encoding="utf-8"))
    except ET.ParseError as exc:
        raise InputError(str(path), "an SVG file (XML)", str(exc)) from None
    for el in root.iter():
        if el.tag.rsplit("}", 1)[-1] == "path" and el.get("d"):
            try:
                return svg_polygon(el.get("d", ""), arc_tolerance=arc_tolerance, svg_scale=svg_scale)
            except InputError as exc:
                raise InputError(f"{path}: path d", exc.expected, exc.got) from None
    raise InputError(str(path), "an SVG file with a <path d=...> element", "none")


def outline_from(value: object, *, arc_tolerance: float = ARC_TOLERANCE,
                 svg_scale: float = SVG_SCALE) -> shapely.Polygon:
    """The outline [m] that ``value`` describes.

    ``value`` is a shapely polygon, a list of points ``[[x, y], ...]`` [m], SVG path data (a string
    starting with ``M``), or the path of a file: ``.svg`` (its first ``<path>``) or a tool YAML file
    (its ``outline``).

    Raises:
        InputError: naming the file or the field and what was expected.
    """
    if isinstance(value, shapely.Polygon):
        return _checked(np.asarray(value.exterior.coords)[:-1], "outline")
    if isinstance(value, str) and _PATH_START.match(value):
        return svg_polygon(value, arc_tolerance=arc_tolerance, svg_scale=svg_scale)
    if isinstance(value, str | Path):
        path = Path(value)
        if not path.is_file():
            raise InputError(str(path), "an outline file (.svg or a tool .yaml) or SVG path data", "no such file")
        if path.suffix.lower() == ".svg":
            return _svg_file(path, arc_tolerance, svg_scale)
        from tooltransfer.yaml_file import read_yaml

        def error(source: str, where: str, expected: str, got: object) -> InputError:
            return InputError(f"{source}: {where}", expected, None if got is None else str(got))

        data = read_yaml(path, error, "tool file")
        if not isinstance(data, dict) or "outline" not in data:
            raise InputError(f"{path}: outline", "a tool file with an outline", "no outline field")
        outline = data["outline"]
        if isinstance(outline, str):
            return svg_polygon(outline, arc_tolerance=arc_tolerance, svg_scale=svg_scale)
        return _checked(outline, f"{path}: outline")
    return _checked(value, "outline")
