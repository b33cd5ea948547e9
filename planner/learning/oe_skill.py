"""Learning the universal OE skill from demonstrations with tool 1 (docs/design.md section 5, steps 1-3).

A demonstration, for the OE skill, is its ordered pushes (:class:`DemoPush`): which face pushed,
the object track during the push and the tool heading. Switches are left out of the OE time axis
(the object stands still while the tool goes round it; the SS skill learns those moves).

Recovery into the universal space (the paper's Fig. 8b), push by push:

1. the object track of each push is smoothed by a least-squares polynomial in time (degree 5);
2. each step's direction relative to the face's push direction at that heading, ``theta``, is
   mapped back through the exact inverse of (6): the universal direction ``phi + theta_g``, same
   step length. A universal angle is a direction, so ``|theta_g|`` stops at pi: condensed angles
   closer to the cone's edge than ``theta_b exp(-k pi / theta_b)`` are clipped (motions along or
   outside the cone's edge come back as pushing straight backwards at most);
3. the universal steps are integrated from one fixed point to the next, and the mismatch at the
   next one is spread along the stretch in proportion to arc length (fixed points: the corners
   where the active face changes, plus the start and the end; they stay pinned).

One DMP is then fitted on every recovered demonstration (one phase, eq. 4 over all of them).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tooltransfer.dmp import DMP
from tooltransfer.errors import InputError, SkillFileError
from tooltransfer.planner.learning.oe_mappings import angle_inverse, wrap_angle
from tooltransfer.problems.task import MAPPING_K
from tooltransfer.tools.model import Tool
from tooltransfer.validation import check_array
from tooltransfer.versioned_json import check_format, format_tag, read_json, write_versioned

OE_NAME, OE_VERSION = "tooltransfer.oe", 1
"""Name and version of the OE skill format."""
OE_FORMAT = format_tag(OE_NAME, OE_VERSION)


@dataclass(frozen=True)
class DemoPush:
    """One demonstrated push.

    Attributes:
        face: the pushing face of the demonstration tool.
        t: sample times (K,) [s], increasing.
        object_xy: object centre (K, 2) [m].
        tool_yaw: tool heading (K,) [rad] at the same times.
    """

    face: str
    t: NDArray[np.float64]
    object_xy: NDArray[np.float64]
    tool_yaw: NDArray[np.float64]

    def __post_init__(self) -> None:
        t = check_array(self.t, "push.t", ndim=1)
        if t.size < 3 or np.any(np.diff(t) <= 0):
            raise InputError("push.t", "at least 3 increasing times [s]", f"{t.size} samples")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "object_xy", check_array(self.object_xy, "push.object_xy", shape=(t.size, 2)))
        object.__setattr__(self, "tool_yaw", check_array(self.tool_yaw, "push.tool_yaw", shape=(t.size,)))


@dataclass(frozen=True)
class Recovered:
    """A demonstration in the universal space: times (N,) [s] on the OE axis (switches removed),
    positions (N, 2) [m], the fixed points (F, 2) [m] (start, fixed corners, end), and ``starts``
    (P+1,): push i covers the samples ``starts[i]`` to ``starts[i+1]`` inclusive (neighbouring
    pushes share their corner)."""

    t: NDArray[np.float64]
    x: NDArray[np.float64]
    fixed: NDArray[np.float64]
    starts: NDArray[np.intp]

    @property
    def bounds(self) -> NDArray[np.float64]:
        """Push boundaries (P+1,) [s]."""
        return self.t[self.starts]


SMOOTH_DEGREE = 5
"""Degree of the least-squares polynomial in time fitted to each push's object track. A depth
camera's 1-2 mm noise is as large as one 30 Hz step of a slow push and the inverse of (6) amplifies
direction noise, so each push (a smooth move between two stops) is fitted as a whole; degree 5
holds a minimum-jerk move exactly."""


def _smooth(t: NDArray[np.float64], x: NDArray[np.float64]) -> NDArray[np.float64]:
    """Smoothed positions (K, 2) of a push's track ``x`` (K, 2) on times ``t`` (K,)."""
    deg = min(SMOOTH_DEGREE, t.size - 1)
    fits = [np.polynomial.Polynomial.fit(t, x[:, j], deg) for j in range(2)]
    return np.column_stack([f(t) for f in fits])


def _similarity(path: NDArray[np.float64], end: NDArray[np.float64]) -> NDArray[np.float64]:
    """Pin ``path`` (K, 2) to end at ``end`` (2,): the mismatch is spread along the path in proportion
    to arc length (a turn-and-scale about the start would blow short stretches up)."""
    seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
    total = float(seg.sum())
    frac = np.concatenate([[0.0], np.cumsum(seg)]) / total if total > 0 else np.linspace(0.0, 1.0, len(path))
    return path + frac[:, None] * (end - path[-1])


def _mid_direction(p: DemoPush, push_angle: float) -> NDArray[np.float64]:
    """The face's world push direction [rad] at the middle of each step (K-1,)."""
    yaw = np.unwrap(p.tool_yaw)
    return 0.5 * (yaw[1:] + yaw[:-1]) + push_angle


def _map_steps(
    steps: NDArray[np.float64], phi: NDArray[np.float64], theta_b: float, k: float, *, inverse: bool
) -> NDArray[np.float64]:
    """Steps (K-1, 2) turned about the push directions ``phi`` by (6) (condensing) or by its
    inverse (recovering), lengths kept: exact inverses of each other step by step."""
    from tooltransfer.planner.learning.oe_mappings import angle_map

    theta = wrap_angle(np.arctan2(steps[:, 1], steps[:, 0]) - phi)
    if inverse:
        # a universal angle is a direction: beyond +-pi it would wrap, so condensed angles are
        # clipped where their preimage reaches pi, theta_b (1 - exp(-k pi / theta_b))
        edge = theta_b * -np.expm1(-k * np.pi / theta_b) * (1.0 - 1e-12)
        theta = angle_inverse(np.clip(theta, -edge, edge), theta_b, k)
    else:
        theta = angle_map(theta, theta_b, k)
    ang = phi + theta
    return np.linalg.norm(steps, axis=1)[:, None] * np.column_stack([np.cos(ang), np.sin(ang)])


def recover(pushes: Sequence[DemoPush], tool: Tool, k: float, fixed: Sequence[int] | None = None) -> Recovered:
    """Recover one demonstration (its pushes in order) into the universal space.

    Args:
        pushes: the demonstration's pushes; push ``i+1`` starts where push ``i`` ends (a corner).
        tool: the demonstration tool; k: adjusting factor of (6).
        fixed: indices of the corners kept as fixed points (corner ``i`` is where push ``i`` ends,
            ``0 <= i < P - 1``); default every corner (docs/design.md section 5). The start and the end are
            always fixed. Between two fixed points the universal steps of the pushes in between are
            integrated and the stretch is pinned onto its end. With every corner fixed
            a straight push comes back as itself (only the curvature within a push opens up); with
            fewer fixed points a staircase of pushes opens up into the universal motion.
    """
    if not pushes:
        raise InputError("pushes", "at least one push")
    n_p = len(pushes)
    corners = set(range(n_p - 1)) if fixed is None else set(fixed)
    if any(not 0 <= c < n_p - 1 for c in corners):
        raise InputError("fixed", f"corner indices in [0, {n_p - 2}]", sorted(corners))
    ends = sorted(corners | {n_p - 1})
    ts, vs, starts = [pushes[0].t[:1] * 0.0], [], [0]
    clock = 0.0
    for p in pushes:
        face = tool.face(p.face)
        xs = _smooth(p.t, p.object_xy)
        vs.append(_map_steps(np.diff(xs, axis=0), _mid_direction(p, face.push_angle), face.theta_b, k, inverse=True))
        ts.append(p.t[1:] - p.t[0] + clock)
        clock = float(ts[-1][-1])
        starts.append(starts[-1] + p.t.size - 1)
    steps = np.vstack(vs)
    x = np.zeros((steps.shape[0] + 1, 2))
    anchor = pushes[0].object_xy[0]
    first = 0
    for e in ends:
        lo, hi = starts[first], starts[e + 1]
        stretch = np.vstack([anchor, anchor + np.cumsum(steps[lo:hi], axis=0)])
        x[lo : hi + 1] = _similarity(stretch, pushes[e].object_xy[-1])
        anchor, first = pushes[e].object_xy[-1], e + 1
    pins = np.array([pushes[0].object_xy[0]] + [pushes[e].object_xy[-1] for e in ends])
    return Recovered(np.concatenate(ts), x, pins, np.array(starts))


@dataclass
class OESkill:
    """The universal OE skill: a 2-D DMP plus what it was learned from.

    Attributes:
        dmp: the fitted DMP (its ``tau`` is the mean demonstration duration [s]).
        k: adjusting factor used for the recovery.
        tool: name of the demonstration tool.
        recovered: the recovered demonstrations (for figures and round trips).
    """

    dmp: DMP
    k: float
    tool: str
    recovered: list[Recovered]

    def to_dict(self) -> dict[str, Any]:
        """Plain-data description, format ``tooltransfer.oe/1``: the DMP (``tooltransfer.dmp/1``),
        the recovery's ``k``, the demonstration tool and the recovered demonstrations."""
        return {
            "format": OE_FORMAT, "k": self.k, "tool": self.tool, "dmp": self.dmp.to_dict(),
            "recovered": [{"t": r.t.tolist(), "x": r.x.tolist(), "fixed": r.fixed.tolist(),
                           "starts": r.starts.tolist()} for r in self.recovered],
        }

    @classmethod
    def from_dict(cls, doc: Any, source: str = "<dict>") -> OESkill:
        """Rebuild a skill from :meth:`to_dict` output; another format or damaged data raises
        :class:`~tooltransfer.errors.SkillFileError`."""
        check_format(doc, OE_NAME, OE_VERSION, source)
        try:
            rec = [Recovered(np.asarray(r["t"], float), np.asarray(r["x"], float), np.asarray(r["fixed"], float),
                             np.asarray(r["starts"], np.intp)) for r in doc["recovered"]]
            k = float(doc["k"])
            if not 0.0 < k < 1.0:
                raise ValueError(f"k = {k} is not in (0, 1)")
            return cls(DMP.from_dict(doc["dmp"], source), k, str(doc["tool"]), rec)
        except (KeyError, TypeError, ValueError) as exc:
            raise SkillFileError(source, f"damaged OE skill ({exc})") from None

    def save(self, path: str | Path) -> Path:
        """Write the skill as JSON (:meth:`to_dict`), atomically
        (:func:`tooltransfer.versioned_json.write_versioned`); returns its path."""
        return write_versioned(path, self.to_dict())

    @classmethod
    def load(cls, path: str | Path) -> OESkill:
        """Read a skill written by :meth:`save`; another format or a damaged file raises
        :class:`~tooltransfer.errors.SkillFileError`."""
        return cls.from_dict(read_json(path), str(path))


def learn_oe_skill(
    demos: Sequence[Sequence[DemoPush]],
    tool: Tool,
    *,
    k: float = MAPPING_K,
    n_basis: int = 30,
    scaling: str = "similarity",
    fixed: Sequence[Sequence[int] | None] | None = None,
) -> OESkill:
    """Recover every demonstration and fit one DMP on all of them (docs/design.md section 5, steps 2-3).

    Args:
        demos: per demonstration, its pushes in order.
        tool: the demonstration tool (tool 1).
        k: adjusting factor of (6), in (0, 1).
        n_basis: basis functions per dimension; scaling: the DMP's forcing-term scaling mode
            (``"similarity"`` by default: a new start-to-target vector turns and scales the shape).
        fixed: per demonstration, the corners kept as fixed points (see :func:`recover`); default
            every corner.
    """
    if not demos:
        raise InputError("demos", "at least one demonstration")
    per_demo = list(fixed) if fixed is not None else [None] * len(demos)
    if len(per_demo) != len(demos):
        raise InputError("fixed", f"one entry per demonstration ({len(demos)})", len(per_demo))
    rec = [recover(d, tool, k, f) for d, f in zip(demos, per_demo, strict=True)]
    dmp = DMP(2, n_basis=n_basis, scaling=scaling)  # type: ignore[arg-type]
    dmp.fit([r.t for r in rec], [r.x for r in rec])
    return OESkill(dmp, k, tool.name, rec)


def condense_recovered(rec: Recovered, pushes: Sequence[DemoPush], tool: Tool, k: float) -> NDArray[np.float64]:
    """Condense a recovered demonstration again with the demonstration's own faces and headings:
    universal directions through (6), integrated push by push between the demonstration's corners. Returns the
    condensed positions (N, 2) [m] on ``rec.t``; with the demonstration's (smoothed) track they
    measure the round trip."""
    out: list[NDArray[np.float64]] = []
    for i, p in enumerate(pushes):
        face = tool.face(p.face)
        seg = rec.x[rec.starts[i] : rec.starts[i + 1] + 1]
        steps = _map_steps(np.diff(seg, axis=0), _mid_direction(p, face.push_angle), face.theta_b, k, inverse=False)
        a, b = (out[-1][-1] if out else rec.x[0]), p.object_xy[-1]
        path = _similarity(np.vstack([a, a + np.cumsum(steps, axis=0)]), b)
        out.append(path if i == 0 else path[1:])
    return np.vstack(out)
