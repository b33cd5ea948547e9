"""The options of the ``qp`` variant of OE condensing (:mod:`tooltransfer.planner.planning.oe.qp_variant`).

The task's ``oe`` fields it reads keep the task schema's defaults, bounds and descriptions
(:class:`tooltransfer.problems.task.OEOptions`); the search's own fields are declared here.
"""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field

from tooltransfer.problems.task import OEOptions

__all__ = ["TASK_FIELDS", "QPOptions"]

_TASK = OEOptions.model_fields
#: The task's ``oe`` fields the ``qp`` variant uses: their defaults, bounds and descriptions are the
#: task schema's (:class:`tooltransfer.problems.task.OEOptions`), reused, not written again.
TASK_FIELDS = ("n_samples", "n_basis", "segments", "max_pushes", "candidates", "switch_price", "max_contacts",
               "friction_cone_fraction", "friction_cone_fraction_max", "guided_budget", "contact_margin",
               "contact_span")


class QPOptions(BaseModel):
    """Options of the ``qp`` variant: the task's ``oe`` fields of :data:`TASK_FIELDS` (defaults,
    bounds and descriptions of :class:`tooltransfer.problems.task.OEOptions`) and the search's own.
    Validated once, by pydantic, when built (:meth:`from_task` takes the task's already validated
    values); ``model_copy(update=...)`` makes a variant of it.

    Attributes:
        screen_samples: constraint-grid samples while candidates are ranked (a coarser grid; the
            best candidates are then solved again on the full grid, the first feasible one wins).
        switch_price: cost of one face change [m^2], in the units of the objective (half the mean
            squared deviation): the default weighs a face change like 0.63 mm of RMS deviation; on the
            transfer case the push count depends on it (benchmarks/README.md).
        ridge: weight of a ridge on the weights [m^2 per weight^2]; 0 by default (tracking on more
            samples than basis functions is already well posed; weights are O(100), so even 1e-10
            outweighs a millimetre of deviation).
        tol: violation [m, m/s] the fit aims at (rows violated by more are added). 1e-6 (1 um/s,
            10 um over a 10 s push): at 1e-7 and below the linearised cone and contact rows of a later
            sequential round admit spurious infeasibility proofs (benchmarks/README.md);
        accept: largest true violation [m, m/s] of a candidate still counted feasible (the heading
            cone is exact only where it was linearised, so rounds stop a little short of ``tol``);
        max_scp: sequential-convex rounds per candidate.
        scp_rtol: the sequential-convex loop stops when the objective changes by less than this
            (relative) and the path meets every linearised row (screening fits use
            ``SCREEN_RTOL``: ranking needs no more);
        recontact_price: cost of one re-contact [m^2] (half a face change by default: a short move
            of the same face, no switch round the object);
        alternatives: further screened candidates a plan may hand out (``PushPlan.next_best``) when a
            later stage fails on it (a switch that finds no path, a check that fails).
        friction_cone_fraction: share (0, 1] of the friction cone's half-angle ``atan(mu)`` the
            planned object directions may use about a face's normal (a plan that survives an error in
            ``mu``: :meth:`tooltransfer.planner.planning.oe.face_frame.FaceFrame.build`).
        friction_cone_fraction_max: the widest share the guided search may use where no plan keeps to
            ``friction_cone_fraction`` (:func:`tooltransfer.planner.planning.oe.guided.guided_plans`).
        guided_budget: expansions of the guided search per attempt.
        guided_contact_span: the narrower stretch of a face [m] the guided search's attempts on windows
            keep the contact on (where the Omni cannot hold the tool at both ends of
            ``contact_span``; the contact then re-touches more often).
        contact_margin, contact_span: where on a face the contact may be [m]
            (:func:`tooltransfer.planner.planning.oe.contacts.usable_range`).
        contact_windows: per face, the arc lengths ``(lo, hi)`` [m] the contact keeps to instead of
            ``contact_span`` about the face's middle (the guided search's choice where the Omni holds
            a face only with its contact toward one end; empty by default).
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    n_samples: int = _TASK["n_samples"]
    screen_samples: int = Field(60, ge=1, strict=True)
    n_basis: int = _TASK["n_basis"]
    segments: int = _TASK["segments"]
    max_pushes: int = _TASK["max_pushes"]
    candidates: int = _TASK["candidates"]
    switch_price: float = _TASK["switch_price"]
    ridge: float = Field(0.0, ge=0, allow_inf_nan=False)
    tol: float = Field(1e-6, gt=0, allow_inf_nan=False)
    accept: float = Field(1e-6, gt=0, allow_inf_nan=False)
    max_scp: int = Field(12, ge=1, strict=True)
    max_contacts: int = _TASK["max_contacts"]
    alternatives: int = Field(4, ge=0, strict=True)
    recontact_price: float = Field(1e-7, ge=0, allow_inf_nan=False)
    scp_rtol: float = 1e-6
    friction_cone_fraction: float = _TASK["friction_cone_fraction"]
    friction_cone_fraction_max: float = _TASK["friction_cone_fraction_max"]
    guided_budget: int = _TASK["guided_budget"]
    guided_contact_span: float = Field(0.004, gt=0, allow_inf_nan=False)
    contact_margin: float = _TASK["contact_margin"]
    contact_span: float = _TASK["contact_span"]
    contact_windows: dict[str, tuple[float, float]] = Field(default_factory=dict)

    @classmethod
    def from_task(cls, oe: OEOptions) -> QPOptions:
        """The options of a task's ``oe`` section (validated by the task schema, so not again), the
        search's own fields at their defaults."""
        return cls.model_construct(**oe.model_dump(include=set(TASK_FIELDS)))
