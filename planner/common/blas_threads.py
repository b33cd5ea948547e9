"""One BLAS thread for the command line, unless the user chose a number.

The planner's matrices have a few dozen to a few hundred rows: handing such products to a BLAS
thread per core costs more in start-up and hand-over than it gains, and on cores other work also
uses it costs CPU time as well (figures in ``benchmarks/README.md``). OpenBLAS and MKL read their
thread counts once, when NumPy loads them, so :func:`pin_blas_threads` must run before NumPy is
imported: the ``tooltransfer`` command calls it first thing (:func:`tooltransfer.planner.apps.cli.main`,
which imports nothing heavy before), and the processes it starts (the batch's task runners, Dask's
local workers) inherit the setting. A user who sets any of :data:`THREAD_VARIABLES` keeps their choice.

It imports nothing heavy.
"""

from __future__ import annotations

import os
from collections.abc import MutableMapping

#: The variables through which a user chooses BLAS's threads (OpenBLAS reads ``OPENBLAS_NUM_THREADS``, else
#: ``OMP_NUM_THREADS``; MKL ``MKL_NUM_THREADS``, else ``OMP_NUM_THREADS``).
THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
#: What :func:`pin_blas_threads` sets: the BLAS libraries' own variables (``OMP_NUM_THREADS`` would also
#: bind every other OpenMP library).
PINNED = {"OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def pin_blas_threads(environ: MutableMapping[str, str] = os.environ) -> bool:
    """Set :data:`PINNED` in ``environ`` unless one of :data:`THREAD_VARIABLES` is set there (to anything
    but an empty string); returns whether it set them. Effective only before NumPy loads."""
    if any(environ.get(name) for name in THREAD_VARIABLES):
        return False
    environ.update(PINNED)
    return True


__all__ = ["PINNED", "THREAD_VARIABLES", "pin_blas_threads"]
