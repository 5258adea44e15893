"""View objects: a strategy record turned into the checked pieces the templates print.

The seed's code writers "extract the appropriate values from the strategy record, substitute
them into the appropriate slots in code skeletons, and print the results" (§4.7, L2484). Here
the extraction is :func:`program_view`; the skeletons are ``templates/*.al.j2``. Every number
and every branch of the program is settled in this module, from the record — the templates
only iterate over view fields and test whether an optional piece is present:

- *tap* (L2516–2519): emitted when the record has a :class:`~synth.strategies.records.Tap`;
- *first attempt* (L2731–2737): ``MOVE pin TO target VIA approach, approach vias…`` — the
  record's via points along the hole axis (they bound the joint-interpolated path's bow), the
  same shifted to each search point;
- *search* (L2520–2530): emitted when the record has a
  :class:`~synth.strategies.records.Search`, otherwise the perfunctory check
  ``IF ABS(DISTANCE_OFF) > threshold THEN ABORT(...)``. The planner decided (seed: Δx > Δr_ok);
  the threshold is the record's ``success_threshold`` (seed-al-subset.md §6: ``T*(d1−d2)``
  does not reproduce the printed .169/.239, so the planner owns that number).

Names: the task's frames and the arm's names come from the world binding
(:func:`synth.codegen.binding.bind_world`), and every name the record uses must be one of them and
pass :func:`synth.al.names.al_name_problem` again. The program's own variables
(``DISTANCE_OFF``, ``CORR``, ``FLAG``, ``R``, ``DW``, ``W``, ``X``, ``Y``, ``SETPNT``; S:2737–2760)
get a numeric suffix when the task already uses the name, so a task frame called ``FLAG`` is
never overwritten.

One representation choice is made here rather than in the record: the search loop's ring
limit is printed as ``(rings + ½)·step`` instead of the seed's ``rings·step`` (1.72 = 3 × .572
rounded), so that neither the three-digit rounding of the limit nor the accumulation
``R ← R + step`` can add or drop a ring: the loop runs exactly ``rings`` rings.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from synth.al.names import RESERVED
from synth.codegen import literals as L
from synth.codegen.binding import bind_world
from synth.codegen.literals import Fragment
from synth.codegen.motion import Guard, MoveView, Waypoint, motion_sequence
from synth.exceptions import CodegenError
from synth.models.graph import AttributeGraph
from synth.strategies.records import (
    WORLD_BASE,
    Destination,
    PinInHoleStrategy,
    grasp_remarks,
)

__all__ = [
    "AttemptView",
    "CheckView",
    "FootprintView",
    "HeaderView",
    "LetGoView",
    "PickupView",
    "ProgramView",
    "SearchView",
    "TapView",
    "missed_message",
    "program_view",
]

FULL_CIRCLE = 2.0 * math.pi
"""One turn of the search ring [rad] (the OCR'd ``W<259°DEG`` of L2755 is a full circle)."""

GRASP_FAILED = "GRASP FAILED"
EXPECTED_FORCE = "EXPECTED A FORCE HERE"


# --------------------------------------------------------------------------------------------
# Views, one per skeleton


@dataclass(frozen=True)
class FootprintView:
    """The error footprint in the header (seed PH FP DX/DY/ROT and PH DZ, L2706–2709)."""

    dx: Fragment
    dy: Fragment
    zeta: Fragment
    dz: Fragment


@dataclass(frozen=True)
class HeaderView:
    """``{ PIN-IN-HOLE STRATEGY name: DROK = … FPX = … EXPECTED TIME = … }`` (L2715–2717).

    The seed printed the last figure as ESTIMATED TIME; the program names it as the text does.

    With a tap, the Δz the insertion faces after it (``Tap.dz_after``; the variation's header
    prints that figure, DZ = .188, L2806) follows the footprint's own Δz.
    """

    name: Fragment
    dr_ok: Fragment
    footprint: FootprintView | None
    dz_after_tap: Fragment | None
    expected_time: Fragment


@dataclass(frozen=True)
class PickupView:
    """``write_pickup`` (L2490–2503): open, approach and grasp, centre, affix, depart."""

    omega: Fragment
    gamma: Fragment
    distance: Fragment
    remarks: Fragment | None
    fingers: Fragment
    hand: Fragment
    pin: Fragment
    approach_opening: Fragment
    approach: tuple[MoveView, ...]
    grasp_opening: Fragment
    grasp_failed: Fragment
    departure: tuple[MoveView, ...]
    relocate: Fragment | None = None
    """``hand*TRANS(grasp⁻¹)``: where the pin is believed once CENTER has registered the hand
    on it, when its start location was uncertain (the record's GRASP DETERM, L2244)."""


@dataclass(frozen=True)
class TapView:
    """The tap (L2821–2827): a guarded move through the surface, then ``CORR ← …``."""

    moves: tuple[MoveView, ...]
    correction: Fragment
    place: Fragment
    pin: Fragment


@dataclass(frozen=True)
class AttemptView:
    """The first attempt (L2731–2737): guarded insertion, then ``DISTANCE_OFF ← …``."""

    moves: tuple[MoveView, ...]
    distance_off: Fragment
    seated: Fragment
    pin: Fragment
    correction: Fragment | None


@dataclass(frozen=True)
class CheckView:
    """The perfunctory check when no search is needed (L2520–2525, L2836–2837)."""

    distance_off: Fragment
    threshold: Fragment
    message: Fragment


@dataclass(frozen=True)
class SearchView:
    """The search loop over the error footprint (L2738–2778, as clean AL).

    Rings of radius ``ring_step, 2·ring_step, …`` while ``radius ≤ ring_limit``; on each, angles
    ``0, Δw, 2Δw, …`` below ``full_circle`` with ``Δw = (ring_step/R)*RAD``; a point (X, Y) is
    tried when ``|X| ≤ half_x`` and ``|Y| ≤ half_y``, at
    ``SETPNT = hole*TRANS(NILROTN, ROT(ZHAT, zeta)*VECTOR(X, Y, 0))``. With a ``retreat``
    (the record's ``off_surface = "retract"``) the point's guarded move has no arrival abort;
    a point where the pin went deeper than the seated depth by more than the threshold
    (``DISTANCE_OFF < below``: nothing was felt) is backed out of along the hole axis to its
    approach point, and the loop goes on.
    """

    missed: Fragment
    distance_off: Fragment
    threshold: Fragment
    flag: Fragment
    radius: Fragment
    step_angle: Fragment
    angle: Fragment
    x: Fragment
    y: Fragment
    setpnt: Fragment
    rings: Fragment
    ring_step: Fragment
    ring_limit: Fragment
    start_angle: Fragment
    full_circle: Fragment
    half_x: Fragment
    half_y: Fragment
    hole: Fragment
    zeta: Fragment
    zero_length: Fragment
    moves: tuple[MoveView, ...]
    seated: Fragment
    pin: Fragment
    correction: Fragment | None
    message: Fragment
    retreat: MoveView | None
    below: Fragment | None
    beside: Fragment | None
    first_retreat: MoveView | None = None
    """Where a first attempt that felt nothing backs out to before the loop (the record's
    ``first_off_surface = "retract"``): its approach point above the believed hole."""


@dataclass(frozen=True)
class LetGoView:
    """Let go (L2779–2781): open the fingers, unfix the pin from the hand."""

    fingers: Fragment
    opening: Fragment
    pin: Fragment
    hand: Fragment


@dataclass(frozen=True)
class ProgramView:
    """The whole program, piece by piece; ``tap`` and ``search``/``check`` are the branches."""

    header: HeaderView
    pickup: PickupView
    tap: TapView | None
    attempt: AttemptView
    search: SearchView | None
    check: CheckView | None
    let_go: LetGoView
    get_clear: tuple[MoveView, ...]


# --------------------------------------------------------------------------------------------
# Names


class _Names:
    """The names a program may use: the task's frames, the arm's names, fresh variables."""

    def __init__(self, graph: AttributeGraph) -> None:
        binding = bind_world(graph)
        self.frames = frozenset(f.al_name.upper() for f in binding.frames)
        self.hands = frozenset(h.upper() for h in binding.hand_names)
        self.task = graph.spec.name
        self._taken: set[str] = set(self.frames | self.hands | RESERVED)

    def frame(self, value: str, field: str) -> Fragment:
        """A task frame (``PIN1``, ``BH1``): a valid AL name the task binds."""
        fragment = L.name(value, field=field)
        if fragment.text not in self.frames:
            raise CodegenError(field, f"{value!r} is not a frame of task {self.task!r}")
        return fragment

    def hand(self, value: str, field: str) -> Fragment:
        """One of the arm's names (``BMANIP``, ``BHAND``)."""
        fragment = L.name(value, field=field, role="arm")
        if fragment.text not in self.hands:
            known = ", ".join(sorted(self.hands))
            raise CodegenError(field, f"{value!r} is not a name of the arm ({known})")
        return fragment

    def movable(self, value: str, field: str) -> Fragment:
        """A destination's frame or base: the hand or a task frame."""
        if isinstance(value, str) and value.upper() in self.hands:
            return self.hand(value, field)
        return self.frame(value, field)

    def variable(self, stem: str) -> Fragment:
        """A program variable named ``stem``, or ``stem1``, ``stem2``… if the task uses it."""
        candidate, k = stem, 0
        while candidate.upper() in self._taken:
            k += 1
            candidate = f"{stem}{k}"
        self._taken.add(candidate.upper())
        return L.name(candidate, field=f"variable {stem}")


# --------------------------------------------------------------------------------------------
# Checks on record numbers


def _positive(value: float, field: str) -> float:
    if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
        raise CodegenError(field, f"expected a positive finite number, got {value!r}")
    return float(value)


def _waypoint(
    names: _Names, d: Destination, field: str, *, base: Fragment | None = None
) -> Waypoint:
    if base is None and d.base != WORLD_BASE:
        base = names.movable(d.base, f"{field}.base")
    return Waypoint(
        what=names.movable(d.what, f"{field}.what"), base=base, xf=d.xf, field=f"{field}.xf"
    )


# --------------------------------------------------------------------------------------------
# Builders


def _header(s: PinInHoleStrategy) -> HeaderView:
    e = s.errors
    footprint = None
    if e is not None:
        footprint = FootprintView(
            dx=L.length(e.dx, field="errors.dx"),
            dy=L.length(e.dy, field="errors.dy"),
            zeta=L.angle(e.zeta, field="errors.zeta"),
            dz=L.length(e.dz, field="errors.dz"),
        )
    return HeaderView(
        name=L.comment(s.name),
        dr_ok=L.length(s.dr_ok, field="dr_ok"),
        footprint=footprint,
        dz_after_tap=None if s.tap is None else L.length(s.tap.dz_after, field="tap.dz_after"),
        expected_time=L.duration(s.expected_time, field="expected_time"),
    )


def _pickup(s: PinInHoleStrategy, names: _Names, pin_: Fragment) -> PickupView:
    p = s.pickup
    if p.object.upper() != pin_.text:
        raise CodegenError("pickup.object", f"picks up {p.object!r}, not the pin {s.pin!r}")
    approach = motion_sequence(
        [
            *(_waypoint(names, d, "pickup.approach_detour") for d in p.approach_detour),
            _waypoint(names, p.approach_point, "pickup.approach_point"),
            _waypoint(names, p.grasp_point, "pickup.grasp_point"),
        ],
        field="pickup.approach_point",
    )
    # the transport's detour continues the departure: one unguarded MOVE of the pin, ending
    # above the approach point, where the guarded first attempt (or the tap) starts
    departure = motion_sequence(
        [
            _waypoint(names, p.departure_point, "pickup.departure_point"),
            *(_waypoint(names, d, "transport_detour") for d in s.transport_detour),
        ],
        field="pickup.departure_point",
    )
    return PickupView(
        omega=L.angle(p.grasp.omega, field="pickup.grasp.omega"),
        gamma=L.angle(p.grasp.gamma, field="pickup.grasp.gamma"),
        distance=L.length(p.grasp.distance, field="pickup.grasp.distance"),
        # the generator's remark restates the grasp the comment's first line gives
        remarks=None if p.remarks in ("", grasp_remarks(p.grasp)) else L.comment(p.remarks),
        fingers=names.hand(s.fingers, "fingers"),
        hand=names.hand(s.hand, "hand"),
        pin=pin_,
        approach_opening=L.length(
            _positive(p.approach_opening, "pickup.approach_opening"),
            field="pickup.approach_opening",
        ),
        approach=approach,
        grasp_opening=L.length(
            _positive(p.grasp_opening, "pickup.grasp_opening"), field="pickup.grasp_opening"
        ),
        grasp_failed=L.string(GRASP_FAILED),
        departure=departure,
        # CENTER moved the arm onto the true pin: re-derive the pin from the hand, or AFFIX
        # would keep the start location's error in the grip the program believes.
        relocate=None
        if p.grasp_determination is None
        else L.pose(
            names.hand(s.hand, "hand"), p.grasp.pin_from_hand().inverse(), field="pickup.grasp"
        ),
    )


def _guard(s: PinInHoleStrategy, pin_: Fragment) -> Guard:
    threshold = _positive(s.force_threshold, "force_threshold")
    return Guard(
        frame=pin_,
        force=L.force(threshold, field="force_threshold"),
        message=L.string(EXPECTED_FORCE),
    )


def missed_message(s: PinInHoleStrategy) -> str:
    """The ABORT text of a run whose pin missed its hole: ``PIN1 MISSED BH1``.

    The search's abort, and with ``UNEXPECTEDLY.`` after it the single check's; the pipeline
    tells a miss from other failures by it.
    """
    return f"{L.name(s.pin, field='pin').text} MISSED {L.name(s.hole, field='hole').text}"


def program_view(strategy: PinInHoleStrategy, graph: AttributeGraph) -> ProgramView:
    """All pieces of the program for ``strategy`` in ``graph``'s task (see the module doc).

    Raises :class:`~synth.exceptions.CodegenError` naming the record field when a name is not
    a valid AL name of the task, a number is not finite or not positive where it must be, or a
    guarded motion would have to be split.
    """
    s = strategy
    names = _Names(graph)
    pin_ = names.frame(s.pin, "pin")
    hole = names.frame(s.hole, "hole")
    hand = names.hand(s.hand, "hand")
    guard = _guard(s, pin_)
    threshold = L.length(
        _positive(s.success_threshold, "success_threshold"), field="success_threshold"
    )
    distance_off = names.variable("DISTANCE_OFF")

    tap = None
    correction = None
    if s.tap is not None:
        correction = names.variable("CORR")
        tap = TapView(
            moves=motion_sequence(
                [
                    _waypoint(names, s.tap.via, "tap.via"),
                    _waypoint(names, s.tap.target, "tap.target"),
                ],
                guard=guard,
                field="tap",
            ),
            correction=correction,
            place=_waypoint(names, s.tap.place, "tap.place").location,
            pin=pin_,
        )

    first_retracts = s.search is not None and s.search.first_off_surface == "retract"
    attempt = AttemptView(
        moves=motion_sequence(
            [
                _waypoint(names, s.approach, "approach"),
                *(_waypoint(names, v, "approach_vias") for v in s.approach_vias),
                _waypoint(names, s.target, "target"),
            ],
            guard=replace(guard, message=None) if first_retracts else guard,
            field="target",
        ),
        distance_off=distance_off,
        seated=_waypoint(names, s.destination, "destination").location,
        pin=pin_,
        correction=correction,
    )

    missed = missed_message(s)
    search = None
    check = None
    if s.search is not None:
        search = _search(s, names, pin_, hole, guard, threshold, distance_off, correction, missed)
    else:
        check = CheckView(
            distance_off=distance_off,
            threshold=threshold,
            message=L.string(f"{missed} UNEXPECTEDLY."),
        )

    opening = _positive(s.let_go_opening, "release_opening")
    return ProgramView(
        header=_header(s),
        pickup=_pickup(s, names, pin_),
        tap=tap,
        attempt=attempt,
        search=search,
        check=check,
        let_go=LetGoView(
            fingers=names.hand(s.fingers, "fingers"),
            opening=L.length(opening, field="release_opening"),
            pin=pin_,
            hand=hand,
        ),
        get_clear=motion_sequence([_waypoint(names, s.get_clear, "retreat")], field="retreat"),
    )


def _search(
    s: PinInHoleStrategy,
    names: _Names,
    pin_: Fragment,
    hole: Fragment,
    guard: Guard,
    threshold: Fragment,
    distance_off: Fragment,
    correction: Fragment | None,
    missed: str,
) -> SearchView:
    search = s.search
    assert search is not None
    step = _positive(search.step, "search.step")
    if not (isinstance(search.rings, int) and search.rings >= 1):
        raise CodegenError("search.rings", f"expected a whole number ≥ 1, got {search.rings!r}")
    flag = names.variable("FLAG")
    radius = names.variable("R")
    step_angle = names.variable("DW")
    angle = names.variable("W")
    x = names.variable("X")
    y = names.variable("Y")
    setpnt = names.variable("SETPNT")

    def shifted(d: Destination, field: str) -> Waypoint:
        if d.base.upper() != hole.text:
            raise CodegenError(
                f"{field}.base",
                f"search offsets are in the hole frame {hole.text}, not {d.base!r}",
            )
        return _waypoint(names, d, field, base=setpnt)

    retract = None
    if search.off_surface == "retract":
        (retract,) = motion_sequence([shifted(s.approach, "approach")], field="approach")
    elif search.off_surface != "abort":
        raise CodegenError("search.off_surface", f"abort or retract, not {search.off_surface!r}")
    first_retreat = None
    if search.first_off_surface == "retract":
        if retract is None:
            raise CodegenError(
                "search.first_off_surface", "the first attempt retracts only when the search does"
            )
        waypoint = _waypoint(names, s.approach, "approach")
        (first_retreat,) = motion_sequence([waypoint], field="approach")
    elif search.first_off_surface != "abort":
        raise CodegenError(
            "search.first_off_surface", f"abort or retract, not {search.first_off_surface!r}"
        )
    threshold_m = _positive(s.success_threshold, "success_threshold")

    return SearchView(
        missed=L.comment(missed),
        distance_off=distance_off,
        threshold=threshold,
        flag=flag,
        radius=radius,
        step_angle=step_angle,
        angle=angle,
        x=x,
        y=y,
        setpnt=setpnt,
        rings=L.dimensionless(search.rings, field="search.rings"),
        ring_step=L.length(step, field="search.step"),
        ring_limit=L.length((search.rings + 0.5) * step, field="search.rings"),
        start_angle=L.angle(0.0),
        full_circle=L.angle(FULL_CIRCLE),
        half_x=L.length(_positive(search.dx, "search.dx"), field="search.dx"),
        half_y=L.length(_positive(search.dy, "search.dy"), field="search.dy"),
        hole=hole,
        zeta=L.angle(search.zeta, field="search.zeta"),
        zero_length=L.length(0.0),
        moves=motion_sequence(
            [
                shifted(s.approach, "approach"),
                *(shifted(v, "approach_vias") for v in s.approach_vias),
                shifted(s.target, "target"),
            ],
            guard=guard if retract is None else replace(guard, message=None),
            field="target",
        ),
        seated=shifted(s.destination, "destination").location,
        pin=pin_,
        correction=correction,
        message=L.string(missed),
        retreat=retract,
        below=None if retract is None else L.length(-threshold_m, field="success_threshold"),
        beside=None if retract is None else L.comment(f"NOTHING FELT: {pin_.text} WENT BESIDE"),
        first_retreat=first_retreat,
    )
