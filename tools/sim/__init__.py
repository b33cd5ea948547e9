"""The simulated platform: the Omni with a tool and the puck in MuJoCo (:mod:`tools.sim.mjcf`),
driven by PD tracking of joint or tool paths (:mod:`tools.sim.platform`)."""

from tools.sim.mjcf import SimParams, build_mjcf
from tools.sim.platform import ContactEvent, Execution, Rates, SimPlatform

__all__ = ["ContactEvent", "Execution", "Rates", "SimParams", "SimPlatform", "build_mjcf"]
