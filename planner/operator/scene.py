"""The demonstration task; defined in :mod:`tooltransfer.problems.scenes` (kept here for existing imports)."""

from tooltransfer.problems.scenes import DEMO_SCENE, DemoScene

__all__ = ["DEMO_SCENE", "DemoScene"]
