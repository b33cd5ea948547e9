"""``tooltransfer tools derive OUTLINE``: a tool file with the faces derived from an outline.

OUTLINE is a tool YAML file (its ``outline``, ``name`` and ``a_t``), an ``.svg`` file (its first
path), SVG path data (``"M 0 0 L ..."``), or a JSON list of points ``[[x, y], ...]`` [m]
(:func:`tooltransfer.tools.derive.outline_from`). The derived tool is printed as YAML or written
with ``-o``; ``--plot`` draws the outline with its contacts, normals and cones; ``--json`` prints
every contact instead.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

from tooltransfer.planner.common.command_line import EXIT_OK


def add_derive_parser(tools: argparse.ArgumentParser, add: Any) -> None:
    """The ``derive`` sub-command of ``tools`` (``add``: the CLI's sub-parser helper)."""
    from tooltransfer.tools.derive.defaults import (
        ARC_TOLERANCE,
        DEFAULT_C,
        DEFAULT_FRICTION,
        MAX_DERIVED_FACES,
        MIN_LENGTH,
    )

    sub = tools.add_subparsers(dest="tools_command", metavar="{derive}")
    p = add(sub, "derive", "derive a tool's contact faces from its outline and write the tool file",
            "tooltransfer tools derive head.svg --name head -o head.yaml --plot head.png", cmd_derive)
    p.add_argument("outline", help="tool YAML file, .svg file, SVG path data ('M ...'), or a JSON list of "
                   "points [[x, y], ...] [m]")
    p.add_argument("-o", "--out", dest="tool_out", type=Path, default=None,
                   help="write the tool file (YAML) here (default: print it)")
    p.add_argument("--plot", type=Path, default=None, help="draw the outline, faces, normals and cones here (PNG)")
    p.add_argument("--json", action="store_true", help="print every derived contact as JSON")
    p.add_argument("--name", default=None, help="tool name (default: the tool file's, else the file's stem)")
    p.add_argument("--a-t", type=float, default=None, help="tool length a_t [m] (default: the tool file's, else 0.026)")
    p.add_argument("--radius", type=float, default=0.0175, help="object radius [m] (default 0.0175)")
    p.add_argument("--friction", type=float, default=DEFAULT_FRICTION,
                   help=f"tool-object friction mu (default {DEFAULT_FRICTION})")
    p.add_argument("--c", type=float, default=DEFAULT_C, help=f"limit-surface ratio c (default {DEFAULT_C})")
    p.add_argument("--min-length", type=float, default=MIN_LENGTH,
                   help=f"shortest usable edge part that makes a face [m] (default {MIN_LENGTH})")
    p.add_argument("--max-faces", type=int, default=MAX_DERIVED_FACES,
                   help=f"most faces kept, the longest usable parts (default {MAX_DERIVED_FACES})")
    p.add_argument("--arc-tolerance", type=float, default=ARC_TOLERANCE,
                   help=f"largest distance of an SVG curve from its chords [m] (default {ARC_TOLERANCE})")
    p.add_argument("--svg-scale", type=float, default=1e-3, help="metres per SVG unit (default 0.001: mm)")


def _source(text: str) -> tuple[Any, dict[str, Any]]:
    """What ``outline_from`` takes for ``text``, and the tool file's fields when it is one."""
    from tooltransfer.errors import InputError

    stripped = text.strip()
    if stripped.startswith("["):
        try:
            return json.loads(stripped), {}
        except json.JSONDecodeError as exc:
            raise InputError("outline", "a JSON list of points [[x, y], ...] [m]", str(exc)) from None
    path = Path(text)
    if path.suffix.lower() in (".yaml", ".yml") and path.is_file():
        from tooltransfer.yaml_file import read_yaml

        def error(source: str, where: str, expected: str, got: object) -> InputError:
            return InputError(f"{source}: {where}", expected, None if got is None else str(got))

        data = read_yaml(path, error, "tool file")
        return text, data if isinstance(data, dict) else {}
    return text, {}


def cmd_derive(args: argparse.Namespace) -> int:
    from tooltransfer.atomic import write_text
    from tooltransfer.errors import InputError
    from tooltransfer.tools.derive import derive_faces, outline_from
    from tooltransfer.tools.library import dump_tool
    from tooltransfer.tools.model import Tool
    from tooltransfer.tools.omni.platform import OmniPlatform

    value, fields = _source(args.outline)
    outline = outline_from(value, arc_tolerance=args.arc_tolerance, svg_scale=args.svg_scale)
    name = args.name or fields.get("name") or (Path(args.outline).stem if Path(args.outline).is_file() else "derived")
    a_t = args.a_t if args.a_t is not None else fields.get("a_t", 0.026)
    if isinstance(a_t, bool) or not isinstance(a_t, int | float) or not 0 < a_t <= 0.2:
        raise InputError("--a-t", "a tool length in (0, 0.2] m", repr(a_t))
    d = derive_faces(outline, args.radius, args.friction, c=args.c, min_length=args.min_length,
                     max_faces=args.max_faces, platform=OmniPlatform(a_t=float(a_t)))
    notes = str(fields.get("notes", "")) + (
        f"\nFaces derived from the outline (tooltransfer tools derive): object radius {args.radius:g} m, "
        f"mu {args.friction:g}, c {args.c:g}, shortest usable part {args.min_length:g} m.")
    tool = Tool(str(name), outline, d.faces, float(a_t), str(fields.get("description", "")), notes.strip())
    text = dump_tool(tool)
    if args.plot is not None:
        from tooltransfer.planner.apps.cli_output import written
        from tooltransfer.planner.apps.plots.derived_faces import plot_derivation

        with written(args.plot) as tmp:
            plot_derivation(d, tmp, f"{name}: derived contacts (radius {args.radius * 1e3:g} mm, "
                                    f"mu {args.friction:g})")
    if args.tool_out is not None:
        write_text(args.tool_out, text)
    if args.json:
        print(json.dumps(_contacts(d), indent=1))
    elif args.tool_out is None:
        print(text, end="")
    else:
        for e in d.edges:
            used = "face" if any(f.name == e.name for f in d.faces) else "unused"
            print(f"{e.name}: {used}, usable {e.usable_length * 1e3:.1f} mm of {e.length * 1e3:.1f} mm, normal "
                  f"{math.degrees(e.normal_angle):.1f} deg, cone +-{math.degrees(e.friction_half):.1f} deg, "
                  f"sideways travel per contact {e.travel * 1e3:.2f} mm")
        print(f"{len(d.vertices)} convex vertices (point contacts); wrote {args.tool_out}")
    return EXIT_OK


def _contacts(d: Any) -> dict[str, Any]:
    return {
        "object_radius": d.radius, "friction": d.friction, "c": d.c,
        "faces": [f.name for f in d.faces],
        "edges": [{"name": e.name, "segment": [e.start.tolist(), e.end.tolist()],
                   "contact_range": list(e.contact_range), "normal_angle": e.normal_angle,
                   "friction_half_angle": e.friction_half, "sideways_travel": e.travel,
                   "world_directions": list(e.world_directions) if e.world_directions else None,
                   "on_platform": e.on_platform} for e in d.edges],
        "vertices": [{"name": v.name, "point": v.point.tolist(), "normal_angles": list(v.normals),
                      "friction_half_angle": v.friction_half} for v in d.vertices],
    }
