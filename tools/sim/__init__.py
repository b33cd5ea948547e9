"""The simulated platform: the Omni carrying a tool, with the puck and obstacles, in MuJoCo.

* :mod:`tooltransfer.tools.sim.config`: :class:`SimConfig`, the physical and numerical settings.
* :mod:`tooltransfer.tools.sim.mjcf`: the MJCF model written from the DH table, the tool and the scene, and why
  each contact setting has its value.
* :mod:`tooltransfer.tools.sim.model`: :class:`SimModel`, the compiled model, its addresses and the rollout.
* :mod:`tooltransfer.tools.sim.reference`: joint references on the physics steps, tool paths through the IK.
* :mod:`tooltransfer.tools.sim.execution`: :class:`Execution` (recorded tracks and :class:`ContactEvent` s) and
  :class:`Rates`.
* :mod:`tooltransfer.tools.sim.recorder`: sensor rows to an :class:`Execution` (sampling, faces, events).
* :mod:`tooltransfer.tools.sim.platform`: :class:`SimPlatform`, stateful: reset, execute in chunks, observe.
* :mod:`tooltransfer.tools.sim.batch`: :func:`execute_many`, many executions on a thread pool.
* :mod:`tooltransfer.tools.sim.scenarios`: scripted pushes (a straight push, the sideways sweep that shows the
  heading drift) used by the tests, the benchmark and ``planner/apps/plots/heading_drift.py``.

SI units and the world frame of docs/design.md section 2 throughout.
"""

from typing import Any

from tooltransfer.lazy import lazy_attribute

#: Each public name and its submodule, imported on first use: ``config``, ``execution``, ``mjcf`` and
#: ``reference`` need no mujoco (the optional ``sim`` extra), so checking or exporting a plan does not.
_HOMES = {
    "CONTACT_GAP": "execution", "ContactEvent": "execution", "Execution": "execution", "Rates": "execution",
    "Job": "batch", "execute_many": "batch", "SimConfig": "config", "build_mjcf": "mjcf", "SimModel": "model",
    "SimPlatform": "platform",
}
__all__ = sorted(_HOMES)


def __getattr__(name: str) -> Any:
    return lazy_attribute(__name__, _HOMES, name)
