"""Generalizing the universal OE skill to a new start and target (docs/design.md section 5, step 4)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.dmp import DMP
from tooltransfer.errors import InputError
from tooltransfer.validation import check_array, check_positive


def generalize(
    skill: DMP, start: ArrayLike, target: ArrayLike, *, n_samples: int = 400, duration: float | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Roll the universal OE skill out from ``start`` to ``target`` [m] (2,).

    The skill's scaling mode decides how the demonstrated shape adapts to the new start-to-target
    vector (``"none"`` as the paper, ``"amplitude"``, ``"similarity"``). ``duration`` [s] defaults
    to the demonstrations' mean duration (the skill's ``tau``).

    Returns:
        ``t`` (n,) [s], positions (n, 2) [m], velocities (n, 2) [m/s].
    """
    if skill.n_dims != 2:
        raise InputError("skill", "a planar (2-D) OE skill", f"{skill.n_dims}-D")
    x0 = check_array(start, "start", shape=(2,))
    g = check_array(target, "target", shape=(2,))
    if not isinstance(n_samples, int) or n_samples < 3:
        raise InputError("n_samples", "an integer >= 3", repr(n_samples))
    tau = skill.tau if duration is None else check_positive(duration, "duration")
    t = np.linspace(0.0, tau, n_samples)
    roll = skill.rollout(t, x0=x0, g=g, tau=tau)
    return roll.t, roll.x, roll.v
