"""The demonstration task; defined in :mod:`problems.scenes` (kept here for existing imports)."""

from problems.scenes import DEMO_SCENE, DemoScene

__all__ = ["DEMO_SCENE", "DemoScene"]
