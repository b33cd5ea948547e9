"""The windows of an ``unknown`` verdict's stored ``holds`` (:mod:`.holds_at`), read without the planner: what
``batch report`` and the verdict benchmark count (a start or target held only on windows narrower than the guided
search's narrowest)."""

from __future__ import annotations

from typing import Any

#: A hold narrower than this [m] on every face is narrower than the guided search's narrowest contact
#: windows (:data:`~tooltransfer.planner.planning.oe.guided_rungs.NARROW` of the default ``guided_contact_span``,
#: 4 mm): its attempts hold a window only where both of its ends are held.
NARROW_HOLD = 0.002


def widest_stored(holds: list[dict[str, Any]]) -> float:
    """The widest window [m] over the faces of one end of an evidence's ``holds`` as stored
    (:meth:`.holds_at.FaceHold.to_dict` per face); -1 where no face holds the puck there."""
    return max((hi - lo for h in holds for lo, hi in h.get("windows", [])), default=-1.0)


def narrowly_held(evidence: dict[str, Any]) -> bool:
    """Whether an ``unknown`` verdict's ``evidence`` has its start or its target held only on windows narrower
    than :data:`NARROW_HOLD` (or held nowhere) by its ``holds`` (False without them)."""
    holds = evidence.get("holds")
    return isinstance(holds, dict) and any(widest_stored(holds[end]) < NARROW_HOLD
                                           for end in ("start", "target") if isinstance(holds.get(end), list))
