"""The attempts of the guided search's ladder (:func:`~tooltransfer.planner.planning.oe.guided.guided_plans`):
what each changes in the options (the share of the friction cone, the contact span) and in the search
(:func:`~tooltransfer.planner.planning.oe.guided.guided_path`'s settings), in the order they are made.
"""

from __future__ import annotations

from typing import NamedTuple

from tooltransfer.planner.planning.oe.guided_close import CLOSE_ROOM
from tooltransfer.planner.planning.oe.guided_moves import MAX_WINDOWS, REACH_SLACK, face_cone
from tooltransfer.planner.planning.oe.qp_options import QPOptions
from tooltransfer.planner.planning.setting import Setting

#: The share of the friction cone's half-angle tried before the widest (``friction_cone_fraction_max``),
#: where that is wider: plans keep the most margin that lets them exist.
MIDDLE_SHARE = 0.8

#: Searches again per share of the friction cone, each without the changes of face refused so far.
REFUSALS = 2

#: The weight of the distance to go in the order of the attempts on windows where needed (``mixed``;
#: weighted A*, :func:`~.guided.guided_path`'s ``greed``): with the windows of every face its lattice is several
#: times larger, and the shortest path is not needed, only one the fit can follow.
GREED = 3.0
#: Room [m] the attempts on windows where needed keep between the tool outline and the obstacles at
#: their nodes (the other attempts :data:`~.guided_moves.REACH_SLACK`): the fit places the contact
#: anywhere in a window and the tool turns between nodes, so its plans pass nearer (0.4-0.8 mm on the
#: verdict benchmark); with REACH_SLACK they broke the 0.25 mm hard check or left the closed loop's corrections no room.
LAST_ROOM = 0.001
#: Searches again in the attempts on windows where needed without the changes of face refused so far
#: (each a cheap search: a switch with no tool path in reach often recurs a few millimetres further on).
LAST_REFUSALS = 5

#: The share of ``guided_contact_span`` the ladder's narrow attempt spans its windows with (a contact held
#: only within a millimetre or two of one place, where no wider window is held at both of its ends).
NARROW = 0.5
#: The most windows per face of the narrow attempt (odd): they overlap on faces up to ten spans long (the
#: library's l_shape foot, 12 mm); on longer ones they are spread with gaps between them.
NARROW_WINDOWS = 11
#: The narrow attempt's expansions, as a multiple of the other fine attempts' (its lattice holds a face's
#: every window where the whole face is not held).
NARROW_BUDGET = 2
#: The share of ``guided_contact_span`` the ladder's closest attempt spans its windows with (1 mm by default:
#: a way within half a millimetre of an obstacle, :mod:`~.guided_close`).
CLOSE = 0.25
#: The closest attempt's expansions, as a multiple of the other fine attempts' (on the verdict benchmark the one
#: task it solves takes under 2,000; where it finds nothing it costs 15-60 s CPU per task at this budget).
CLOSE_BUDGET = 1


class _Rung(NamedTuple):
    """One attempt of :func:`~.guided.guided_plans`' ladder: the options it changes (``change``: the share of the
    friction cone, the contact span) and the search's settings (as :func:`~.guided.guided_path` takes them; ``fine``:
    steps and cells of a :data:`~.guided.FINE` share of the usual and ``1 / FINE`` times the expansions;
    ``refusals``: how many times it searches again without a change of face a later stage refused;
    ``widest``: at ``friction_cone_fraction_max`` beyond the ladder's middle share; ``guide``: ordered by
    the distance to go of :func:`~.guided.guide_field`; ``spent``: made only where an attempt before on whole steps
    and whole faces ended on its budget, not its space; ``most``: the most contact windows per face;
    ``scale``: the attempt's expansions as a multiple of ``oe.guided_budget`` (on fine steps, of theirs);
    ``narrow``: the attempt on windows of a :data:`NARROW` share of the span where the whole face is not
    held; ``close``: the ladder's last rung, on windows of a :data:`CLOSE` share, with the steps and room
    of :mod:`~.guided_close`)."""

    change: dict[str, float]
    windows: bool = False
    more: bool = False
    fine: bool = False
    mixed: float | None = None
    greed: float = 1.0
    room: float = REACH_SLACK
    refusals: int = REFUSALS
    widest: bool = False
    guide: bool = False
    spent: bool = False
    most: int = MAX_WINDOWS
    scale: int = 1
    narrow: bool = False
    close: bool = False

    @property
    def whole_faces(self) -> bool:
        """Whether the search holds each face as a whole (no contact windows, not even where the whole is
        not held)."""
        return not self.windows and self.mixed is None

    @property
    def last(self) -> bool:
        """Whether this is one of the ladder's last attempts, for tasks with no plan at all (not made after a
        plan kept with little room)."""
        return self.guide or self.spent or self.narrow or self.close



def _ladder(setting: Setting, options: QPOptions) -> list[_Rung]:
    """The attempts of :func:`~.guided.guided_plans`, in order (its docstring), before it leaves out those the
    attempts before them make needless."""
    wide, span = options.friction_cone_fraction_max, options.guided_contact_span
    share = options.friction_cone_fraction
    middle = max(share, min(wide, MIDDLE_SHARE))  # the rung of the ladder below the widest share
    at_middle = {"friction_cone_fraction": middle}
    tries = [_Rung({"friction_cone_fraction": share})]
    if middle > share:
        tries.append(_Rung(at_middle))
    tries.append(_Rung(at_middle, more=True))
    windowed = span < options.contact_span
    if windowed:
        tries.append(_Rung({**at_middle, "contact_span": span}, windows=True, more=True))
    tries.append(_Rung(at_middle, more=True, fine=True))

    def mixed_rung(change: dict[str, float], widest: bool = False) -> _Rung:
        return _Rung(change, more=True, fine=True, mixed=span, greed=GREED, room=LAST_ROOM, refusals=LAST_REFUSALS,
                     widest=widest)

    tries += [mixed_rung(at_middle)] if windowed else []
    if wide > middle and _widens(setting, middle, wide):  # last of all: plans nearer the cone's edge keep less margin
        at_wide = {"friction_cone_fraction": wide}
        tries += [_Rung(at_wide, more=True, fine=fine, widest=True) for fine in (False, True)]
        tries += [mixed_rung(at_wide, widest=True)] if windowed else []
    # last of all, where every attempt failed: the middle share's fine steps in the order of the distance field (a
    # path the straight line's order left unexpanded), first on whole faces and windows where needed (fewer pushes,
    # fewer re-contacts), then on every face's windows (a way only windows hold)
    guided = mixed_rung(at_middle)._replace(guide=True)
    tries += [guided, guided._replace(change={**at_middle, "contact_span": span}, mixed=None, windows=True)
              ] if windowed else []
    # last, where a search on whole steps spent its budget: that search weighted toward the target (weighted A*
    # reaches a lattice's far side in fewer expansions; where every space closed, a new order has little to find)
    tries.append(_Rung(at_middle, more=True, greed=GREED, refusals=LAST_REFUSALS, spent=True))
    # last of all: the attempt on windows where needed at the middle share, on narrower windows (a contact held
    # only within a millimetre or two of one place on the face, its rolling kept there by the half steps)
    tries += [mixed_rung(at_middle)._replace(mixed=NARROW * span, most=NARROW_WINDOWS, scale=NARROW_BUDGET,
                                             narrow=True)] if windowed else []
    # last of all: that attempt on windows of a millimetre, the tool nearer the obstacles, each step ending where its
    # face still holds the puck (shrunk where it would not)
    tries += [mixed_rung(at_middle)._replace(mixed=CLOSE * span, most=NARROW_WINDOWS, scale=CLOSE_BUDGET,
                                             room=CLOSE_ROOM, close=True)] if windowed else []
    return tries


def _widens(setting: Setting, narrow: float, wide: float) -> bool:
    """Whether some face's admissible cone is wider at the ``wide`` share of the friction cone's
    half-angle than at the ``narrow`` one (where the tool file's ``push_angle +- theta_b`` is the narrower at
    both, every attempt at ``wide`` would repeat one at ``narrow``: the search and the fit see the same
    cones). A face that can push at neither share counts as unchanged."""
    return any(face_cone(setting, f, wide) != face_cone(setting, f, narrow) for f in setting.tool.faces)
