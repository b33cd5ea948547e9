"""Figures of a batch: success rate against difficulty (obstacle count; distance of start or target
to the reach boundary) with 95% Wilson intervals, and planning-time distributions per variant."""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from planner.batch.report import wilson
from planner.plots.save import save_figure


def _rates(rows: Sequence[dict[str, Any]], key: Any) -> tuple[list, list, list, list]:
    groups: dict[Any, list[bool]] = defaultdict(list)
    for r in rows:
        groups[key(r)].append(r["status"] == "solved")
    xs = sorted(groups)
    rate = [float(np.mean(groups[x])) for x in xs]
    ci = [wilson(int(np.sum(groups[x])), len(groups[x])) for x in xs]
    lo = [r - c[0] for r, c in zip(rate, ci, strict=True)]
    return xs, rate, lo, [c[1] - r for r, c in zip(rate, ci, strict=True)]


def plot_batch(rows: Sequence[dict[str, Any]], out: Path) -> list[Path]:
    """Write ``success_vs_difficulty.png`` and ``time_distributions.png`` into ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    variants = sorted({r["variant"] for r in rows})
    by_var = {v: [r for r in rows if r["variant"] == v] for v in variants}
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2))
    margins = np.array([r["reach_margin"] for r in rows if r.get("reach_margin") is not None], dtype=float)
    edges = np.unique(np.quantile(margins, np.linspace(0, 1, 6))) if margins.size else np.array([0.0, 1.0])
    for k, v in enumerate(variants):
        shift = (k - (len(variants) - 1) / 2) * 0.08
        sub = [r for r in by_var[v] if r.get("n_obstacles") is not None]
        xs, rate, lo, hi = _rates(sub, lambda r: int(r["n_obstacles"]))
        a1.errorbar(np.array(xs) + shift, rate, yerr=[lo, hi], marker="o", capsize=3, label=v)
        sub = [r for r in by_var[v] if r.get("reach_margin") is not None]
        if sub and edges.size > 1:
            def binned(r: dict[str, Any]) -> int:
                return int(np.clip(np.searchsorted(edges, r["reach_margin"], side="right") - 1, 0, edges.size - 2))

            xs, rate, lo, hi = _rates(sub, binned)
            mid = 0.5 * (edges[:-1] + edges[1:])[xs] * 1e3
            a2.errorbar(mid, rate, yerr=[lo, hi], marker="o", capsize=3, label=v)
    a1.set(xlabel="obstacles", ylabel="success rate (solved)", ylim=(-0.03, 1.03),
           title="success against obstacle count (95% Wilson)")
    a1.xaxis.get_major_locator().set_params(integer=True)
    a2.set(xlabel="depth of start/target inside the reach, the smaller [mm] (quintiles)",
           ylabel="success rate (solved)", ylim=(-0.03, 1.03), title="success against reach margin")
    for a in (a1, a2):
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    written = [save_figure(fig, out / "success_vs_difficulty.png")]

    fig, ax = plt.subplots(figsize=(7, 4.2))
    data, labels = [], []
    for v in variants:
        for status in ("solved", "infeasible"):
            t = [r["time_total"] for r in by_var[v] if r["status"] == status and r.get("time_total")]
            if t:
                data.append(np.array(t) * 1e3)
                labels.append(f"{v}\n{status} ({len(t)})")
    if data:
        ax.boxplot(data, whis=(1, 99), showfliers=True, flierprops={"markersize": 2})
        ax.set_xticks(range(1, len(labels) + 1), labels, fontsize=8)
        ax.set_yscale("log")
    ax.set(ylabel="planning time [ms] (log)", title="planning time per variant (whiskers: 1st-99th percentile)")
    ax.grid(alpha=0.3, axis="y")
    written.append(save_figure(fig, out / "time_distributions.png"))
    return written
