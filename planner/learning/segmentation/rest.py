"""Where the object rests between pushes, from the camera samples (docs/design.md section 5, step 1).

Between pushes the object stands still (quasi-static pushing), so its camera samples scatter about
one position with the camera's noise; their mean gives the rest position to ``sigma / sqrt(n)``.
A push that the segmentation missed moves the object in the middle of such a stretch: then only
the samples after that move belong to the rest (:func:`still_tail`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def camera_noise(xy: NDArray[np.float64]) -> float:
    """Robust standard deviation [m] of the camera noise per axis, from successive differences."""
    d = np.abs(np.diff(xy, axis=0))
    return float(np.median(d) / (0.6745 * np.sqrt(2.0))) if d.size else 0.0


def still_tail(xy: NDArray[np.float64], idx: NDArray[np.intp], sigma: float, alpha: float = 1e-4,
               min_tail: int = 3) -> tuple[NDArray[np.intp], bool]:
    """The samples ``idx`` (n,) (time order) of the camera track ``xy`` (M, 2) [m] after the last
    change of the object's mean position, by binary segmentation.

    For a still object and camera noise ``sigma`` [m] per axis, the two-sample statistic of the
    split after the first ``k`` of ``m`` samples, ``k (m - k) / m |mean_left - mean_right|^2 /
    sigma^2``, is chi-squared with 2 degrees of freedom (tail ``exp(-s / 2)``); the best split is a
    change if its statistic exceeds ``2 ln((m - 1) / alpha)``, the Bonferroni bound over the splits,
    so a still object is cut with probability at most ``alpha`` however long it rests (with about
    500 rests in a dataset, ``alpha = 1e-4`` expects fewer than 0.05 false cuts per dataset). The
    search goes on in the samples after each change; at least ``min_tail`` samples are kept.

    Returns:
        The indices after the last change (a suffix of ``idx``) and whether all were kept.
    """
    x = xy[idx]
    s2 = max(sigma, 1e-6) ** 2
    start = 0
    while idx.size - start > min_tail:
        m = idx.size - start
        k = np.arange(1, m - min_tail + 1)  # samples left of the split
        cs = np.cumsum(x[start:], axis=0)
        left, right = cs[k - 1] / k[:, None], (cs[-1] - cs[k - 1]) / (m - k)[:, None]
        stat = k * (m - k) / m * np.sum((left - right) ** 2, axis=1) / s2
        i = int(np.argmax(stat))
        if stat[i] <= 2.0 * np.log((m - 1) / alpha):
            break
        start += int(k[i])
    return idx[start:], start == 0
