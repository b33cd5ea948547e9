"""Figures of the SS skill: learning (like the paper's Fig. 9) and generalized switches of both
variants (like Fig. 11). Each function takes an output path and writes the figure (matplotlib Agg)."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np

from tooltransfer.planner.apps.plots.save import save_figure
from tooltransfer.planner.learning.demo_switch import DemoSwitch
from tooltransfer.planner.learning.switch_skill import SwitchSkill, decompose
from tooltransfer.planner.planning.ss.dmp_variant import recombine
from tooltransfer.planner.planning.ss.result import SwitchPath
from tooltransfer.planner.planning.ss.switch_task import SwitchTask
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.pose import Pose2D


def _figure(ncols: int, nrows: int = 1, size: float = 4.2):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(nrows, ncols, figsize=(size * ncols, size * nrows), squeeze=False)
    return fig, axes


def plot_learned_switches(demos: Sequence[DemoSwitch], skills: Sequence[SwitchSkill], out: str | Path) -> Path:
    """Fig. 9: (a) the demonstrated switches (tool centre point, object and contacts); then per skill
    (one per kind of virtual motion) the aligned demonstrations of the contact point (grey), the
    learned motion (red dashed), the virtual object motion (green dashed) and the pure tool motion
    x^t (blue), all relative to ``x_o = q_A`` [mm]."""
    fig, axes = _figure(1 + len(skills))
    ax = axes[0, 0]
    for d in demos:
        ax.plot(*(1e3 * (d.xy - d.centre)).T, lw=0.8)
        ax.plot(*(1e3 * (np.vstack([d.object_point_from, d.object_point_to]) - d.centre)).T, "k.", ms=4)
    ax.add_patch(_circle((0, 0), 1e3 * demos[0].radius, "darkred"))
    ax.set_title("(a) demonstrated switches (tool centre point)")
    for i, skill in enumerate(skills):
        ax = axes[0, i + 1]
        for j, d in enumerate(demos):
            p = decompose(d, skill.virtual, skill.clearance)
            ax.plot(*(1e3 * p.x).T, color="0.7", lw=0.8, label="demonstrations x" if j == 0 else None)
        t = np.linspace(0.0, skill.tau, 200)
        x = skill.dmp_x.rollout(t, x0=np.zeros(2), g=skill.dmp_x.g).x
        xo = skill.dmp_o.rollout(t, x0=np.zeros(2), g=skill.dmp_o.g).x
        xt = skill.dmp_t.rollout(t, x0=np.zeros(2), g=skill.dmp_t.g).x
        ax.plot(*(1e3 * x).T, "r--", lw=1.6, label="learned x (f)")
        ax.plot(*(1e3 * xo).T, "g--", lw=1.4, label="virtual object x^o (f^o)")
        ax.plot(*(1e3 * xt).T, "b-", lw=1.4, label="pure tool x^t (f^t)")
        ax.plot(0, 0, "ko", ms=4)
        ax.set_title(f"({chr(98 + i)}) virtual motion: {skill.virtual}")
        ax.legend(fontsize=7, loc="best")
    for ax in axes.ravel():
        ax.set_aspect("equal")
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        ax.grid(alpha=0.3)
    return save_figure(fig, out)


def _circle(c, r, color):
    import matplotlib.patches as mpatches

    return mpatches.Circle(c, r, facecolor=color, alpha=0.5, edgecolor=color)


def _draw_path(ax, task: SwitchTask, xy: np.ndarray, yaw: np.ndarray, steps: int = 5) -> None:
    shape = task.shape
    if isinstance(shape, Disc):
        ax.add_patch(_circle(1e3 * shape.centre, 1e3 * shape.radius, "darkred"))
    else:
        ax.fill(*(1e3 * np.asarray(shape.exterior.coords)).T, color="darkred", alpha=0.5)
    for o in task.obstacles:
        if isinstance(o, Disc):
            ax.add_patch(_circle(1e3 * o.centre, 1e3 * o.radius, "0.4"))
        else:
            ax.fill(*(1e3 * np.asarray(o.exterior.coords)).T, color="0.4", alpha=0.6)
    idx = np.linspace(0, len(xy) - 1, steps + 2).round().astype(int)
    for n, k in enumerate(idx):
        poly = Pose2D(*xy[k], yaw[k]).place(task.tool.outline)
        color = "tab:blue" if n == 0 else ("tab:orange" if n == len(idx) - 1 else "0.5")
        ax.plot(*(1e3 * np.asarray(poly.exterior.coords)).T, color=color, lw=1.2 if color != "0.5" else 0.7)
    for name, color in ((task.face_from, "tab:blue"), (task.face_to, "gold")):
        f = task.tool.face(name)
        k = 0 if color == "tab:blue" else len(xy) - 1
        seg = Pose2D(*xy[k], yaw[k]).apply(np.vstack([f.start, f.end]))
        ax.plot(*(1e3 * seg).T, color=color, lw=3)
    ax.plot(*(1e3 * xy).T, "k-", lw=1.0)


#: Fig. 11's own way of solving a switch with a skill variant, where it differs from the variant's
#: (:attr:`tooltransfer.planner.planning.variant_registry.SSVariant.solve`): the recombined path at 40 samples.
FIG11_SOLVERS: dict[str, Callable[[SwitchSkill, SwitchTask], SwitchPath]] = {
    "dmp": lambda skill, task: recombine(skill, task, n_samples=40),
}


def plot_generalized_switches(skill: SwitchSkill, tasks: Mapping[str, SwitchTask], out: str | Path) -> Path:
    """Fig. 11 for the skill variants (:data:`tooltransfer.planner.planning.variant_registry.SS_VARIANTS`): one
    row per task, the ``dmp`` path (left) and the ``opt`` path (right): the tool at the start (blue,
    its first face thick), five internal steps (grey) and the end (orange, the second face in
    yellow), the tool centre point's path, the object (dark red) and the obstacles, and for ``opt``
    the path the NLP started from (green dotted: the ``dmp`` path or a path round the object,
    :mod:`tooltransfer.planner.planning.ss.initial`); each title gives the penetration measured with shapely [mm]."""
    from tooltransfer.planner.planning.variant_registry import SS_VARIANTS

    solvers = {name: FIG11_SOLVERS.get(name, v.solve) for name, v in SS_VARIANTS.items() if v.solve is not None}
    fig, axes = _figure(len(solvers), len(tasks))
    for row, (name, task) in enumerate(tasks.items()):
        for col, (variant, solve) in enumerate(solvers.items()):
            ax = axes[row, col]
            path = solve(skill, task)
            if path.ok:
                _draw_path(ax, task, path.xy, path.yaw)
                if "x_start" in path.info:  # the NLP's start (tooltransfer.planner.planning.ss.initial)
                    start = np.asarray(path.info["x_start"])
                    ax.plot(*(1e3 * start).T, ":", color="tab:green", lw=1.0,
                            label=f"NLP start ({path.info['attempts'][-1]['start']})")
                    ax.legend(fontsize=7, loc="best")
                ax.set_title(f"{name} ({task.tool.name}) {variant}: penetration "
                             f"{1e3 * path.object_penetration:.2f} mm", fontsize=9)
            else:
                ax.set_title(f"{name} {variant}: {path.status}", fontsize=9)
                ax.text(0.5, 0.5, path.reason[:120], transform=ax.transAxes, ha="center", wrap=True, fontsize=7)
            ax.set_aspect("equal")
            ax.set_xlabel("x [mm]")
            ax.set_ylabel("y [mm]")
            ax.grid(alpha=0.3)
    return save_figure(fig, out)
