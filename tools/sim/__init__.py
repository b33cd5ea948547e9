"""The simulated platform: the Omni carrying a tool, with the puck and obstacles, in MuJoCo.

* :mod:`tools.sim.config`: :class:`SimConfig`, the physical and numerical settings.
* :mod:`tools.sim.mjcf`: the MJCF model written from the DH table, the tool and the scene, and why
  each contact setting has its value.
* :mod:`tools.sim.model`: :class:`SimModel`, the compiled model, its addresses and the rollout.
* :mod:`tools.sim.reference`: joint references on the physics steps, tool paths through the IK.
* :mod:`tools.sim.execution`: :class:`Execution` (recorded tracks and :class:`ContactEvent` s) and
  :class:`Rates`.
* :mod:`tools.sim.recorder`: sensor rows to an :class:`Execution` (sampling, faces, events).
* :mod:`tools.sim.platform`: :class:`SimPlatform`, stateful: reset, execute in chunks, observe.
* :mod:`tools.sim.batch`: :func:`execute_many`, many executions on a thread pool.
* :mod:`tools.sim.scenarios`: scripted pushes (a straight push, the sideways sweep that shows the
  heading drift) used by the tests, the benchmark and ``planner/plots/heading_drift.py``.

SI units and the world frame of DESIGN section 2 throughout.
"""

from tools.sim.batch import Job, execute_many
from tools.sim.config import SimConfig
from tools.sim.execution import CONTACT_GAP, ContactEvent, Execution, Rates
from tools.sim.mjcf import build_mjcf
from tools.sim.model import SimModel
from tools.sim.platform import SimPlatform

__all__ = [
    "CONTACT_GAP",
    "ContactEvent",
    "Execution",
    "Job",
    "Rates",
    "SimConfig",
    "SimModel",
    "SimPlatform",
    "build_mjcf",
    "execute_many",
]
