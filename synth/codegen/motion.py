"""Motion sequences: destinations → MOVE statements, as the seed's ``write_motion_sequence``.

Seed §4.7, L2537–2560: the destination list is cut into maximal runs with the same
*controllable* frame (``what``), and each run becomes one ``MOVE what TO ...`` statement. The
seed's sketch prints the first destination after ``TO``; its real output (L2723–2724,
``MOVE BMANIP TO <grasp> VIA <approach>``) puts the **last** destination after ``TO`` and the
earlier ones after ``VIA``, in traversal order — AL visits via points in order, then the
destination (seed-al-subset.md §3, §6). That output is followed here.

Qualifiers are a :class:`Guard` (stop on force, abort on arrival, L2735–2736). Splitting a
guarded sequence into two MOVE statements would change its meaning (L2558: "the semantics of
two successive motion statements are not identical to a single statement, especially where
the qualifiers include stop-on-force tests"); the seed avoided it by care, this module refuses
it with a :class:`~synth.exceptions.CodegenError`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import pinocchio as pin

from synth.codegen.literals import Fragment, pose, trans
from synth.exceptions import CodegenError

__all__ = ["Guard", "MoveView", "Waypoint", "motion_sequence"]


@dataclass(frozen=True, eq=False)
class Waypoint:
    """A checked destination: make ``what`` coincide with ``base*xf`` (seed L1912–1925).

    ``what`` and ``base`` are validated AL names (``base`` may be a program variable such as
    the search loop's ``SETPNT``, or None: ``xf`` is then a world pose); ``xf`` is the constant
    relation [m, rad]; ``field`` names the record field it came from, for error messages.
    """

    what: Fragment
    base: Fragment | None
    xf: pin.SE3
    field: str

    @property
    def location(self) -> Fragment:
        """``base*TRANS(...)``, or ``TRANS(...)`` in the world."""
        if self.base is None:
            return trans(self.xf, field=self.field)
        return pose(self.base, self.xf, field=self.field)


@dataclass(frozen=True)
class Guard:
    """Stop-on-force qualifiers of a guarded move (seed L2735–2736).

    ``ON FORCE(ORIENT(frame)*ZHAT) > force DO STOP`` and ``ON ARRIVAL DO ABORT(message)``: the
    move aims past the expected contact, so arriving means the contact was missed. Without a
    ``message`` there is no arrival clause: the program itself handles a move that felt nothing
    (the search's ``retract``, :data:`synth.strategies.records.OffSurface`).
    """

    frame: Fragment
    force: Fragment
    message: Fragment | None


@dataclass(frozen=True)
class MoveView:
    """One MOVE statement: ``MOVE frame TO destination VIA via[0], ... [guard]``."""

    frame: Fragment
    destination: Fragment
    via: tuple[Fragment, ...]
    guard: Guard | None


def _runs(waypoints: Sequence[Waypoint]) -> list[list[Waypoint]]:
    """Maximal runs of consecutive waypoints with the same controllable frame (L2541–2546)."""
    runs: list[list[Waypoint]] = []
    for w in waypoints:
        if runs and runs[-1][0].what.text == w.what.text:
            runs[-1].append(w)
        else:
            runs.append([w])
    return runs


def motion_sequence(
    waypoints: Sequence[Waypoint], *, guard: Guard | None = None, field: str = "motion"
) -> tuple[MoveView, ...]:
    """MOVE statements visiting ``waypoints`` in order (seed ``write_motion_sequence``, L2537).

    One statement per run of equal ``what``: the run's last waypoint after ``TO``, the earlier
    ones after ``VIA`` in traversal order (the output at L2723–2724). ``guard`` qualifies every
    statement; a guarded sequence that would need more than one statement raises
    :class:`~synth.exceptions.CodegenError` (``field`` names it) instead of being split.
    """
    if not waypoints:
        raise CodegenError(field, "a motion needs at least one destination")
    runs = _runs(waypoints)
    if guard is not None and len(runs) > 1:
        frames = " then ".join(run[0].what.text for run in runs)
        raise CodegenError(
            field,
            f"a guarded motion would be split into {len(runs)} MOVE statements ({frames}); "
            "a stop-on-force clause must qualify one motion",
        )
    return tuple(
        MoveView(
            frame=run[0].what,
            destination=run[-1].location,
            via=tuple(w.location for w in run[:-1]),
            guard=guard,
        )
        for run in runs
    )
