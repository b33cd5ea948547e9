"""The SS (state switching) skill (paper section III.B; DESIGN section 6).

* learning (steps 1-4): :class:`DemoSwitch` (input; :mod:`planner.ss.adapter` converts the
  segmentation's switches, :mod:`planner.ss.synthetic` generates some), virtual object motions
  (:mod:`planner.ss.virtual`: ``"arch"`` or ``"line"``), :func:`learn_switch_skill` ->
  :class:`SwitchSkill` (f, f^o and the pure tool skill f^t of eq. 18), saved as ``tooltransfer.ss/1``;
* the ``dmp`` variant (steps 5-6): :func:`recombine` (new x^o, k1/k2, eq. 18, rollout), measured
  exactly with shapely (:mod:`planner.ss.verify`);
* the ``opt`` variant: :func:`optimize`, a CasADi NLP near the ``dmp`` path (:mod:`planner.ss.nlp`,
  cached per structure), checked with shapely and refined on a violation;
* the domain problem :class:`SwitchTask` and result :class:`SwitchPath`; named cases in
  :mod:`planner.ss.cases`.
"""

from planner.ss.demo import DemoSwitch
from planner.ss.generalize import recombine
from planner.ss.learn import SwitchSkill, learn_switch_skill
from planner.ss.opt import optimize
from planner.ss.result import SwitchPath
from planner.ss.skill_file import load_switch_skill, save_switch_skill
from planner.ss.task import SwitchTask
from planner.ss.virtual import virtual_motion

__all__ = [
    "DemoSwitch",
    "SwitchPath",
    "SwitchSkill",
    "SwitchTask",
    "learn_switch_skill",
    "load_switch_skill",
    "optimize",
    "recombine",
    "save_switch_skill",
    "virtual_motion",
]
