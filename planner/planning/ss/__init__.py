"""The SS (state switching) skill (paper section III.B; docs/design.md section 6).

* learning (steps 1-4): :class:`DemoSwitch` (input; :mod:`tooltransfer.planner.learning.switch_dataset` converts the
  segmentation's switches, :mod:`tooltransfer.planner.planning.ss.synthetic` generates some), virtual object motions
  (:mod:`tooltransfer.planner.learning.virtual_motion`: ``"arch"`` or ``"line"``), :func:`learn_switch_skill` ->
  :class:`SwitchSkill` (f, f^o and the pure tool skill f^t of eq. 18), saved as ``tooltransfer.ss/1``;
* the ``dmp`` variant (steps 5-6): :func:`recombine` (new x^o, k1/k2, eq. 18, rollout), measured
  exactly with shapely (:mod:`tooltransfer.planner.planning.ss.verify`);
* the ``opt`` variant: :func:`optimize`, a CasADi NLP near the ``dmp`` path
  (:mod:`tooltransfer.planner.planning.ss.nlp`, cached per structure), checked with shapely and refined on a violation;
* the domain problem :class:`SwitchTask` and result :class:`SwitchPath`; named cases in
  :mod:`tooltransfer.planner.planning.ss.cases`.
"""

from tooltransfer.planner.learning.demo_switch import DemoSwitch
from tooltransfer.planner.learning.switch_skill import SwitchSkill, learn_switch_skill
from tooltransfer.planner.learning.virtual_motion import virtual_motion
from tooltransfer.planner.planning.ss.dmp_variant import recombine
from tooltransfer.planner.planning.ss.opt_variant import OptOptions, optimize
from tooltransfer.planner.planning.ss.result import SwitchPath
from tooltransfer.planner.planning.ss.switch_task import SwitchTask

__all__ = [
    "DemoSwitch",
    "OptOptions",
    "SwitchPath",
    "SwitchSkill",
    "SwitchTask",
    "learn_switch_skill",
    "optimize",
    "recombine",
    "virtual_motion",
]
