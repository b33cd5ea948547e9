"""The simulated platform: the Omni with a tool and the puck in MuJoCo (:mod:`tools.sim.mjcf`),
driven by PD tracking of joint or tool paths (:mod:`tools.sim.platform`), many at once in a
process pool (:mod:`tools.sim.batch`)."""

from tools.sim.batch import Job, execute_many
from tools.sim.mjcf import SimParams, build_mjcf
from tools.sim.platform import ContactEvent, Execution, Rates, SimPlatform

__all__ = ["ContactEvent", "Execution", "Job", "Rates", "SimParams", "SimPlatform", "build_mjcf", "execute_many"]
