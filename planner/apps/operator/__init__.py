"""A scripted, human-like operator generating demonstrations with tool 1 on the simulated Omni."""

from tooltransfer.planner.apps.operator.operator import DemonstrationFailed, ScriptedOperator, Truth

__all__ = ["DemonstrationFailed", "ScriptedOperator", "Truth"]
