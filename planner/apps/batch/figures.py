"""Figures of a batch: success rate against difficulty (obstacle count; distance of start or target
to the reach boundary) with 95% Wilson intervals, planning-time distributions per variant and, when
plans were executed (``batch run --simulate``), executed success per variant (planned, open and
closed loop within 2 and 5 mm, as shares of all tasks with Wilson intervals) beside the final-error
distributions. Axis units from :mod:`tooltransfer.planner.common.metric_units` (planning times in ms)."""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from tooltransfer.planner.apps.batch.stats import EXEC_TOLS, wilson
from tooltransfer.planner.apps.plots.save import save_figure
from tooltransfer.planner.common.metric_units import display
from tooltransfer.planner.common.metric_units import label as unit_label


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
    """Write ``success_vs_difficulty.png``, ``time_distributions.png`` and, when plans were executed,
    ``executed_success.png`` into ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    variants = sorted({r["variant"] for r in rows})
    by_var = {v: [r for r in rows if r["variant"] == v] for v in variants}
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2))
    _, per_m = display("reach_margin")
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
            mid = 0.5 * (edges[:-1] + edges[1:])[xs] * per_m
            a2.errorbar(mid, rate, yerr=[lo, hi], marker="o", capsize=3, label=v)
    a1.set(xlabel="obstacles", ylabel="success rate (solved)", ylim=(-0.03, 1.03),
           title="success against obstacle count (95% Wilson)")
    a1.xaxis.get_major_locator().set_params(integer=True)
    a2.set(xlabel=unit_label("depth of start/target inside the reach, the smaller", "reach_margin") + " (quintiles)",
           ylabel="success rate (solved)", ylim=(-0.03, 1.03), title="success against reach margin")
    for a in (a1, a2):
        a.grid(alpha=0.3)
        if a.get_legend_handles_labels()[0]:
            a.legend(fontsize=8)
        else:  # no row of the batch has the measure (e.g. a store written before it was recorded)
            a.text(0.5, 0.5, "no rows with this measure", ha="center", va="center", transform=a.transAxes,
                   color="0.4")
    written = [save_figure(fig, out / "success_vs_difficulty.png")]

    fig, ax = plt.subplots(figsize=(7, 4.2))
    _, per_s = display("time_total", "ms")
    data, labels = [], []
    for v in variants:
        for status in ("solved", "violated", "infeasible", "unknown"):
            t = [r["time_total"] for r in by_var[v] if r["status"] == status and r.get("time_total")]
            if t:
                data.append(np.array(t) * per_s)
                labels.append(f"{v}\n{status} ({len(t)})")
    if data:
        ax.boxplot(data, whis=1.5, showfliers=False, medianprops={"color": "k"})
        rng = np.random.default_rng(0)  # the dots' sideways spread: the same figure for the same rows
        for i, d in enumerate(data, start=1):
            ax.plot(i + rng.uniform(-0.18, 0.18, d.size), d, ".", ms=3, color="tab:blue",
                    alpha=max(0.15, min(0.8, 30 / d.size)))
        ax.set_xticks(range(1, len(labels) + 1), labels, fontsize=8)
        ax.set_yscale("log")
    ax.set(ylabel=unit_label("planning time", "time_total", "ms") + " (log)",
           title="planning time per variant (boxes: quartiles; whiskers: 1.5 IQR; dots: every run)")
    ax.grid(alpha=0.3, axis="y")
    written.append(save_figure(fig, out / "time_distributions.png"))
    if any(r.get("open_loop_status") is not None or r.get("closed_loop_status") is not None for r in rows):
        written.append(plot_execution(by_var, out / "executed_success.png"))
    return written


def plot_execution(by_var: dict[str, list[dict[str, Any]]], path: Path) -> Path:
    """Executed success per variant (shares of all tasks, 95% Wilson) and the final errors' CDFs."""
    import matplotlib.pyplot as plt

    u, per_m = display("open_loop_error")
    bars = [("planned", None, None)] + [(f"{name} <= {per_m * tol:g} {u}", key, tol)
                                        for name, key in (("OL", "open_loop"), ("CL", "closed_loop"))
                                        for tol in EXEC_TOLS]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.4))
    width = 0.8 / max(1, len(bars))
    for k, v in enumerate(by_var):
        rows = by_var[v]
        n = len(rows)
        for j, (label, key, tol) in enumerate(bars):
            if key is None:
                hit = sum(r["status"] == "solved" for r in rows)
            else:
                hit = sum(r["status"] == "solved" and r.get(f"{key}_error") is not None
                          and r[f"{key}_error"] <= tol for r in rows)
            rate = hit / n if n else float("nan")
            lo, hi = wilson(hit, n)
            a1.bar(k + (j - (len(bars) - 1) / 2) * width, rate, width, yerr=[[rate - lo], [hi - rate]], capsize=2,
                   color=f"C{j}", label=label if k == 0 else None)
        for key, style in (("open_loop", "--"), ("closed_loop", "-")):
            err = np.sort([r[f"{key}_error"] * per_m for r in rows if r.get(f"{key}_error") is not None])
            if err.size:
                a2.step(np.maximum(err, 1e-2), np.arange(1, err.size + 1) / err.size, where="post", ls=style,
                        color=f"C{k}", label=f"{v} {'OL' if key == 'open_loop' else 'CL'} ({err.size})")
    a1.set_xticks(range(len(by_var)), list(by_var), fontsize=8)
    a1.set(ylabel="share of all tasks", ylim=(0, 1.05), title="planned and executed success (95% Wilson)")
    a1.legend(fontsize=7)
    for tol in EXEC_TOLS:
        a2.axvline(tol * per_m, color="0.6", lw=0.8)
    a2.set_xscale("log")
    a2.set(xlabel=unit_label("final object-to-target error", "open_loop_error") + " (log)",
           ylabel="share of executed plans", ylim=(0, 1.02), title="final error, open loop (dashed) and closed loop")
    if a2.get_legend_handles_labels()[0]:
        a2.legend(fontsize=7)
    for a in (a1, a2):
        a.grid(alpha=0.3)
    return save_figure(fig, path)
