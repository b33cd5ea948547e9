"""Adapting the push model on line: ``mu`` and ``c`` identified again from the pushes just executed.

A robot that pushes in chunks and observes the resting object after each one (the closed loop of
:func:`tooltransfer.planner.execution.closed_loop.execute_closed_loop`) hands every chunk to an
:class:`Adaptation`: the commanded tool poses and the object observed at rest before and after it,
kept as a :class:`~tooltransfer.tools.pushing.identify.RecordedPush`. A chunk the model in force
predicts (:func:`tooltransfer.tools.pushing.forward.simulate`) more than :data:`ADAPT_ERROR` off is
mispredicted; at every second misprediction (an identification costs many runs of the model) the
last :data:`ADAPT_CHUNKS` chunks are fitted by
:func:`~tooltransfer.tools.pushing.identify.identify_mechanics`, started from and pulled towards the
model in force, and the fitted model replaces it when the chunks excite ``mu`` or ``c``.

The identification weighs its prior in units of the chunks' misfit at the model in force, so the
prior's standard deviation here is :data:`ADAPT_PRIOR_SD` times the ratio of that misfit [m] to the
camera's averaged noise [m] (the ratio at least 1): the pull towards the model in force stays that
of a fit within the noise and does not grow with how far the model mispredicts (a strong pull would
keep ``c`` near the model the chunks refute, and the re-plans on the drift that model causes).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from tooltransfer.tools.model import Tool
from tooltransfer.tools.pushing import identify
from tooltransfer.tools.pushing.forward import simulate
from tooltransfer.tools.pushing.identify import RecordedPush
from tooltransfer.tools.pushing.mechanics import PushMechanics

#: A push chunk the model predicted farther off than this [m] counts as mispredicted.
ADAPT_ERROR = 0.001
#: The adaptation identifies the model from at most this many of the last push chunks.
ADAPT_CHUNKS = 6
#: Standard deviation of the adaptation's prior on ``log mu`` and ``log c`` (centred on the model in
#: force) for chunks the model in force fits within the camera's noise (module docstring).
ADAPT_PRIOR_SD = 0.5


@dataclass
class Adaptation:
    """The push chunks executed so far and the model adaptations they led to (module docstring).

    Attributes:
        tool: the pushing tool; radius: the object's radius [m].
        noise: the camera's noise averaged over the frames of one observation [m].
        chunks: the executed chunks, oldest first; mispredicted: how many the model in force
            predicted more than :data:`ADAPT_ERROR` off; times: wall times [s] of the identifications.
    """

    tool: Tool
    radius: float
    noise: float
    chunks: list[RecordedPush] = field(default_factory=list)
    mispredicted: int = 0
    times: list[float] = field(default_factory=list)

    def learn(self, t: NDArray[np.float64], tool_pose: NDArray[np.float64], before: NDArray[np.float64],
              after: NDArray[np.float64], mechanics: PushMechanics) -> tuple[PushMechanics | None, str]:
        """Keep the chunk that moved the tool along ``tool_pose`` (K, 3) at times ``t`` (K,) [s] and the
        object from ``before`` to ``after`` (2,) [m], and identify the model again when it is due.

        Returns the adapted mechanics (None: ``mechanics`` stays in force) and a line for the run's
        log (empty when there is nothing to say). An identification that cannot run leaves the
        model as it is and says why.
        """
        self.chunks.append(RecordedPush(t, tool_pose, np.array([t[-1]]), after[None], before, after,
                                        f"chunk {len(self.chunks)}"))
        predicted = simulate(self.tool, tool_pose, before, self.radius, mechanics).final
        if np.hypot(*(predicted - after)) <= ADAPT_ERROR:
            return None, ""
        self.mispredicted += 1
        if len(self.chunks) < 2 or self.mispredicted % 2:
            return None, ""
        start = time.perf_counter()
        recent = self.chunks[-ADAPT_CHUNKS:]
        miss = [simulate(self.tool, c.tool_pose, c.object_start, self.radius, mechanics).final - c.object_xy[-1]
                for c in recent]
        misfit = float(np.sqrt(np.mean(np.square(miss))))
        try:
            ident = identify.identify_mechanics(self.tool, self.radius, recent, initial=mechanics,
                                                prior_sd=ADAPT_PRIOR_SD * max(1.0, misfit / self.noise),
                                                max_step=5e-4)
        except Exception as exc:  # an identification that cannot run leaves the model as it is
            return None, f"no adaptation ({type(exc).__name__}: {exc})"
        finally:
            self.times.append(time.perf_counter() - start)
        m = ident.mechanics
        if ident.c_excited or ident.mu_excited:
            return m, f"adapted the push model to mu {m.mu:.3f}, c {m.c:.3f} from {len(ident.names)} chunks"
        return None, ""
