"""Identifying the push mechanics (``mu``, ``c``) of a dataset: the dataset-facing side of
:mod:`tooltransfer.tools.pushing.identify`.

The least squares lives in the tools layer and knows nothing of datasets; here the segmentation
(:func:`tooltransfer.planner.learning.segmentation.segment`) finds each push (its contact interval from the encoders)
and the puck's rest positions before and after it (the means of the camera samples while it rests,
robust to a push it missed, projected onto the tool outline where the previous push left it), and
each push is cut into a :class:`~tooltransfer.tools.pushing.identify.RecordedPush`: the encoder poses from
``lead`` before the contact to ``tail`` after its end, the camera samples from the contact to
``rest`` after its end (or to the next push, if that comes first).

Used by ``tooltransfer learn`` (the demonstrations, or a calibration recording made with
``tooltransfer demos --calibration``) through the skills cache (:mod:`tooltransfer.planner.learning.skills`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from tooltransfer.errors import InputError
from tooltransfer.problems.dataset import Dataset, load_dataset
from tooltransfer.tools.pushing.identify import Identification, RecordedPush, identify_mechanics
from tooltransfer.tools.pushing.mechanics import PLATFORM_MECHANICS, PushMechanics
from tooltransfer.validation import check_positive

LEAD, TAIL, REST = 0.15, 0.05, 0.3
"""Default windows [s]: tool poses from ``LEAD`` before the contact starts to ``TAIL`` after it ends
(the tool is then backing off), camera samples until ``REST`` after the end."""


def recorded_pushes(ds: Dataset, segmentations: Sequence | None = None, *, lead: float = LEAD,
                    tail: float = TAIL, rest: float = REST) -> list[RecordedPush]:
    """The pushes of every demonstration of ``ds`` as :class:`RecordedPush` (named ``demo#i``).

    Args:
        ds: the dataset; segmentations: one :class:`tooltransfer.planner.learning.segmentation.Segmentation` per
            demonstration (default: segmented here with the dataset's object radius).
        lead, tail, rest: the windows [s] of the module docstring.
    """
    from tooltransfer.planner.learning.segmentation import segment  # scipy.signal: imported only when identifying

    lead, tail, rest = (check_positive(v, n) for v, n in ((lead, "lead"), (tail, "tail"), (rest, "rest")))
    tool = ds.tool()
    radius = float(ds.meta.object_radius)
    if segmentations is None:
        segmentations = [segment(d, tool, radius=radius) for d in ds.demonstrations]
    if len(segmentations) != len(ds.demonstrations):
        raise InputError("segmentations", f"one per demonstration ({len(ds.demonstrations)})", len(segmentations))
    out: list[RecordedPush] = []
    for d, seg in zip(ds.demonstrations, segmentations, strict=True):
        pushes = seg.pushes
        for i, p in enumerate(pushes):
            before = pushes[i - 1].t_end if i > 0 else -np.inf
            after = pushes[i + 1].t_start if i + 1 < len(pushes) else np.inf
            mt = (d.t_tool >= max(p.t_start - lead, before)) & (d.t_tool <= min(p.t_end + tail, after))
            mo = (d.t_object >= p.t_start) & (d.t_object <= min(p.t_end + rest, after))
            if mt.sum() < 2 or not mo.any():
                continue
            out.append(RecordedPush(d.t_tool[mt], d.tool_pose[mt], d.t_object[mo], d.object_xy[mo],
                                    p.object_before, p.object_after, f"{d.name}#{i}"))
    return out


def identify_dataset(source: str | Path | Dataset, *, initial: PushMechanics = PLATFORM_MECHANICS,
                     **options: float) -> Identification:
    """Identify ``mu`` and ``c`` from every push of a dataset (a folder or a loaded :class:`Dataset`).

    ``options`` go to :func:`tooltransfer.tools.pushing.identify.identify_mechanics` (``max_step``, ``prior_sd``,
    ``excitation_tol``). The result's summary names the dataset folder.

    Raises:
        InputError: the dataset holds no push the segmentation finds.
    """
    ds = source if isinstance(source, Dataset) else load_dataset(source)
    pushes = recorded_pushes(ds)
    if not pushes:
        raise InputError("dataset", "recordings with at least one push of the tool against the puck", str(ds.folder))
    ident = identify_mechanics(ds.tool(), float(ds.meta.object_radius), pushes, initial=initial, **options)
    ident.extra.update({"dataset": str(ds.folder), "tool": ds.meta.tool})
    return ident
