"""Statistics of success rates and the executed-success thresholds, shared by the batch report and its figures."""

from __future__ import annotations

from scipy.stats import binomtest

#: Confidence level of every interval in the batch report and figures.
CONFIDENCE = 0.95
#: Executed success thresholds [m] (final object-to-target distance).
EXEC_TOLS = (0.002, 0.005)


def wilson(k: int, n: int, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """Wilson score interval of a success rate ``k / n`` (``(nan, nan)`` for n = 0)."""
    if n == 0:
        return (float("nan"), float("nan"))
    ci = binomtest(k, n).proportion_ci(confidence_level=confidence, method="wilson")
    return (float(ci.low), float(ci.high))
