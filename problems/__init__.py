"""Task specifications, their schema, and the project's named task files."""

from pathlib import Path

#: The committed demonstrations of tool 1 (the finger) that the paper's cases learn from.
FINGER_DEMOS = Path(__file__).resolve().parent / "data" / "finger_demos"

#: The paper's transfer task: tool 1's demonstrations applied with tool 2 (``tooltransfer paper``, README figures).
PAPER_TRANSFER = Path(__file__).resolve().parent / "paper" / "transfer_tool2.yaml"

#: The variant pairs the paper compares: (OE condensing, SS switch paths), ``mapping``/``qp`` x ``dmp``/``opt``.
PAPER_PAIRS = (("mapping", "dmp"), ("mapping", "opt"), ("qp", "dmp"), ("qp", "opt"))
