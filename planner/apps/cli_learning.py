"""The command line's learning commands: ``demos`` (the scripted operator records a dataset or a
calibration), ``learn`` (the OE and SS skills and the push mechanics into a skills file) and
``segment`` (a dataset's pushes and switches). Each takes the parsed arguments and returns the exit code;
:mod:`tooltransfer.planner.apps.cli` parses and dispatches.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from tooltransfer.planner.apps.cli_output import written
from tooltransfer.planner.common.command_line import EXIT_OK


def cmd_demos(args: argparse.Namespace) -> int:
    import time

    t0 = time.perf_counter()
    if args.calibration:
        from tooltransfer.planner.apps.operator.calibration import generate_calibration
        from tooltransfer.problems.dataset import load_meta

        out = generate_calibration(args.out, seed=args.seed, tool=args.tool)
        n = len(load_meta(out).demonstrations)
        print(f"wrote a calibration recording ({n} trials of straight pushes) to {out} in "
              f"{time.perf_counter() - t0:.1f} s")
        return EXIT_OK
    from tooltransfer.planner.apps.operator.generate import generate_demonstrations

    out = generate_demonstrations(args.out, n=args.n, seed=args.seed, tool=args.tool)
    print(f"wrote {args.n} demonstrations to {out} in {time.perf_counter() - t0:.1f} s")
    return EXIT_OK


def cmd_learn(args: argparse.Namespace) -> int:
    import time

    from tooltransfer.planner.learning.skills import learn_skills

    t0 = time.perf_counter()
    skills = learn_skills(args.dataset, k=args.k, virtual=args.virtual, calibration=args.calibration)
    path = skills.save(args.out)
    ss = skills.ss
    assert ss is not None  # learn_skills(with_ss=True)
    print(f"learned from {args.dataset} in {time.perf_counter() - t0:.1f} s: OE skill (k = {skills.oe.k}, "
          f"{len(skills.oe.recovered)} recovered demonstrations), SS skill ({ss.faces[0]} -> {ss.faces[1]}, "
          f"{ss.n_demos} switches, virtual motion {ss.virtual!r}); wrote {path}")
    m, info = skills.mechanics, skills.identification
    if m is not None and info is not None:
        print(f"push mechanics from {info['n_pushes']} pushes of {info['dataset']} ({info['kind']}): "
              f"mu = {m.mu:.3f} +- {m.mu_std:.3f}, c = {m.c:.3f} +- {m.c_std:.3f}; predicted end positions "
              f"within {1e3 * info['end_error_median']:.2f} mm (median), {1e3 * info['end_error_p90']:.2f} mm (p90)")
        if info["message"]:
            print(f"note: {info['message']}")
    return EXIT_OK


def cmd_segment(args: argparse.Namespace) -> int:
    import numpy as np

    from tooltransfer.planner.learning.segmentation import load_fixed_points, segment
    from tooltransfer.problems.dataset import load_dataset

    ds = load_dataset(args.dataset)
    tool = ds.tool()
    fixed = {} if args.fixed_points is None else load_fixed_points(args.fixed_points,
                                                                    [d.name for d in ds.demonstrations])
    segs = [segment(d, tool, radius=float(ds.meta.object_radius), fixed_points=fixed.get(d.name))
            for d in ds.demonstrations]
    for d, s in zip(ds.demonstrations, segs, strict=True):
        faces = " ".join(f"{p.face}[{p.t_start:.2f}-{p.t_end:.2f}]" for p in s.pushes)
        corners = ", ".join(f"({x:.4f}, {y:.4f})" for x, y in np.asarray(s.fixed_points))
        print(f"{d.name}: {len(s.pushes)} pushes, {len(s.switches)} switches "
              f"({', '.join(f'{w.face_from}->{w.face_to}' for w in s.switches)}), fixed points [m]: {corners}")
        if args.verbose:
            print(f"    {faces}")
    if args.figure:
        from tooltransfer.planner.apps.plots.demonstrations import plot_demonstrations

        with written(args.figure) as tmp:
            plot_demonstrations(ds, segs, tool, tmp)
        print(f"wrote {args.figure}")
    return EXIT_OK


def add_segment_parser(sub: Any, add: Any) -> None:
    """The ``segment`` command's parser on the sub-parsers ``sub`` (``add``: the CLI's command maker)."""
    p = add(sub, "segment", "segment a dataset into pushes and switches (and draw it)",
            "tooltransfer segment problems/data/finger_demos --figure out/demos.png", cmd_segment)
    p.add_argument("dataset", type=Path, help="dataset folder (meta.yaml and CSVs, see the README)")
    p.add_argument("--figure", type=Path, default=None, help="write the figure (Figs. 4b/8a style) here")
    p.add_argument("--fixed-points", type=Path, default=None,
                   help="JSON file {demo name: [[x, y], ...]} [m] overriding the automatic corners")
