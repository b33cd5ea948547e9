"""A scripted, human-like operator generating demonstrations with tool 1 on the simulated Omni."""

from tooltransfer.planner.operator.operator import DemonstrationFailed, ScriptedOperator, Truth
from tooltransfer.planner.operator.scene import DEMO_SCENE, DemoScene

__all__ = ["DEMO_SCENE", "DemoScene", "DemonstrationFailed", "ScriptedOperator", "Truth"]
