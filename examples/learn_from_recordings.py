"""Learn the skills from your own recordings and save a skills file.

Point it at a dataset folder in the ``tooltransfer.dataset/1`` format (``meta.yaml`` and one CSV per
demonstration; the README's "Demonstrations and the dataset format" says what goes in them). It
checks the folder the way the planner reads it, shows what the segmentation finds in each
demonstration (pushes per face, switches), learns the OE and SS skills and the push mechanics
(``mu``, ``c``), and writes one skills file that task files can name (``skills: {file: ...}``).

    python examples/learn_from_recordings.py                              # the committed recordings
    python examples/learn_from_recordings.py path/to/my_dataset -o out/my_skills.json
    python examples/learn_from_recordings.py my_dataset --calibration my_calibration   # mu and c from it
    python examples/learn_from_recordings.py --convert out/examples/converted  # write a dataset from arrays

``--convert DIR`` shows the other half: recordings you hold as arrays (a camera track and an encoder
track, each on its own clock) written as a dataset folder with :func:`tooltransfer.problems.dataset.write_dataset`.
Edit :func:`my_recordings` to read your own logs; here it replays the committed dataset's arrays.
"""

from __future__ import annotations

import argparse
import time
from collections import Counter
from pathlib import Path

import numpy as np

from tooltransfer import problems
from tooltransfer.problems.dataset import Demonstration, Meta, load_dataset, write_dataset

DEMOS = Path(problems.__file__).resolve().parent / "data" / "finger_demos"


def my_recordings() -> tuple[Meta, list[Demonstration]]:
    """Your recordings as arrays: replace the body with the reading of your own logs.

    Per demonstration: the camera's object centres ``object_xy`` (M, 2) [m] at times ``t_object``
    (M,) [s], and the encoders' tool poses ``tool_pose`` (N, 3) (``x, y`` [m], ``yaw`` [rad]) and
    joints ``joints`` (N, 3) [rad] at times ``t_tool`` (N,) [s], all in the world frame of docs/design.md
    section 2 (origin under the Omni's first joint axis, x right, y forward) and on one clock.
    """
    source = load_dataset(DEMOS)
    demos = [Demonstration(d.name, d.t_object, d.object_xy, d.t_tool, d.tool_pose, d.joints)
             for d in source.demonstrations[:3]]
    meta = Meta(
        tool="finger",                      # a library tool, or the path of your tool YAML beside the data
        object_radius=0.0175,               # [m]
        rates={"object_hz": 30.0, "tool_hz": 100.0},
        platform={"a_t": 0.026, "base_xy": (0.0, 0.0), "base_yaw": float(np.pi / 2), "table_height": 0.0},
        demonstrations=[f"{d.name}.csv" for d in demos],
        generator={"converted_by": "examples/learn_from_recordings.py"},
    )
    return meta, demos


def describe(folder: Path) -> None:
    """What the planner will see in the dataset: streams, rates and the segmentation."""
    from tooltransfer.planner.learning.segmentation import segment

    ds = load_dataset(folder)                   # raises DatasetError naming the file, row and column
    tool = ds.tool()
    print(f"{folder}: {len(ds.demonstrations)} demonstrations with tool {tool.name!r}, "
          f"object radius {1e3 * ds.meta.object_radius:.1f} mm")
    for d in ds.demonstrations:
        seg = segment(d, tool, radius=float(ds.meta.object_radius))
        faces = Counter(p.face for p in seg.pushes)
        cam_hz = (d.t_object.size - 1) / (d.t_object[-1] - d.t_object[0])
        enc_hz = (d.t_tool.size - 1) / (d.t_tool[-1] - d.t_tool[0])
        travel = 1e3 * float(np.hypot(*(d.object_xy[-1] - d.object_xy[0])))
        print(f"  {d.name}: {d.t_tool[-1] - d.t_tool[0]:5.1f} s, camera {cam_hz:4.1f} Hz, encoders {enc_hz:5.1f} Hz, "
              f"object moved {travel:5.1f} mm; pushes {dict(faces)}, switches {len(seg.switches)}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dataset", nargs="?", type=Path, default=DEMOS, help="dataset folder (meta.yaml and CSVs)")
    ap.add_argument("-o", "--out", type=Path, default=Path("out/examples/skills.json"), help="skills file to write")
    ap.add_argument("--calibration", type=Path, help="calibration recording to identify mu and c from")
    ap.add_argument("--convert", type=Path, metavar="DIR",
                    help="first write my_recordings() as a dataset folder DIR, then learn from it")
    args = ap.parse_args(argv)

    from tooltransfer.planner.learning.skills import learn_skills

    folder = args.dataset
    if args.convert is not None:
        meta, demos = my_recordings()
        folder = write_dataset(args.convert, meta, demos)
        print(f"wrote {len(demos)} demonstrations to {folder}/ (meta.yaml and CSVs)")
    describe(folder)

    start = time.perf_counter()
    skills = learn_skills(folder, calibration=args.calibration)   # cached by the dataset's content hash
    m = skills.mechanics
    print(f"learned in {time.perf_counter() - start:.1f} s: OE skill from {len(skills.oe.recovered)} recovered "
          f"demonstrations of tool {skills.oe.tool!r} (tau {skills.oe.dmp.tau:.1f} s), "
          f"SS skill {'->'.join(skills.ss.faces)} from {skills.ss.n_demos} switches")
    print(f"push mechanics: mu = {m.mu:.3f} +- {m.mu_std:.3f}, c = {m.c:.3f} +- {m.c_std:.3f}")
    ident = skills.identification or {}
    if ident.get("message"):
        print(f"  note: {ident['message']}")
    if "end_error_median" in ident:
        print(f"  the identified model predicts each push's end within {1e3 * ident['end_error_median']:.2f} mm "
              f"(median), {1e3 * ident['end_error_p90']:.2f} mm (p90) over {ident['n_pushes']} pushes")
    path = skills.save(args.out)
    print(f"wrote {path}: name it in a task file as  skills: {{file: {path.resolve()}}}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
