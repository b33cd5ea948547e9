"""Task specifications, their schema, and the project's named task files."""

from pathlib import Path

#: The committed demonstrations of tool 1 (the finger) that the paper's cases learn from.
FINGER_DEMOS = Path(__file__).resolve().parent / "data" / "finger_demos"
