"""The ``tooltransfer`` command line. Bad input exits with code 2 and a message, never a traceback."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from dmp.errors import ToolTransferError


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="tooltransfer", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="fit a DMP to an L-shaped push with and without cone constraints")
    demo.add_argument("--out", type=Path, default=Path("out/demo"), help="output folder")
    args = parser.parse_args(argv)
    try:
        if args.command == "demo":
            from planner.demo import run_demo

            print(run_demo(args.out))
            print(f"wrote {args.out / 'demo.png'} and {args.out / 'demo.txt'}")
    except ToolTransferError as exc:
        print(f"tooltransfer: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
