"""Strategy records: the decisions of seed §4.1 (L1840–1925), frozen, SI units.

A :class:`PinInHoleStrategy` holds everything code generation needs — every number a template
prints comes from here (the codegen must not decide anything). Destination points follow the
seed's (what, base, xf) form (L1912–1925): make the controllable frame ``what`` coincide with
``base ∘ xf``. ``to_json`` gives the shapes of ``synth plan --json``, which the HTTP API
returns too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.strategies.causes import classify
from synth.units import INCH

if TYPE_CHECKING:
    from synth.strategies.grasp import CenteringBounds


def _se3_json(pose: pin.SE3) -> dict[str, list[float]]:
    return {
        "translation": [float(x) for x in pose.translation],
        "rotation_vector": [float(x) for x in pin.log3(pose.rotation)],
    }


WORLD_BASE = "NILTRANS"
"""The base of a destination given in the world: AL's identity frame."""


@dataclass(frozen=True, eq=False)
class Destination:
    """Make the controllable frame ``what`` coincide with ``base ∘ xf`` (seed L1912–1925).

    ``what`` and ``base`` are AL names (``BMANIP``, ``PIN1``, ``BH1``); ``xf`` is a constant
    transform [m, rad]. ``label`` says which point of the strategy it is (``approach``, …).
    A ``base`` of :data:`WORLD_BASE` makes ``xf`` the frame's world pose (a detour's via
    points, :mod:`synth.strategies.detour`).
    """

    label: str
    what: str
    base: str
    xf: pin.SE3

    def to_json(self) -> dict[str, Any]:
        """JSON form (SI)."""
        return {"label": self.label, "what": self.what, "base": self.base, "xf": _se3_json(self.xf)}


@dataclass(frozen=True)
class Grasp:
    """Grasp parameters of seed §4.3.2 (L2020): ``hand = pin ∘ trans(rot(ẑ,ω)·rot(x̂,γ), (0,0,d))``.

    ``omega`` [rad] turns the hand about the pin axis, ``gamma`` [rad] is the angle between the
    pin axis and the hand's approach vector, ``distance`` [m] is measured from the pin tip.
    """

    omega: float
    gamma: float
    distance: float

    def pin_from_hand(self) -> pin.SE3:
        """``trans(rot(ẑ, ω)·rot(x̂, γ), (0, 0, d))``: the hand in the pin's frame."""
        rotation = pin.exp3(np.array([0.0, 0.0, self.omega])) @ pin.exp3(
            np.array([self.gamma, 0.0, 0.0])
        )
        return pin.SE3(rotation, np.array([0.0, 0.0, self.distance]))

    def to_json(self) -> dict[str, float]:
        """JSON form (SI)."""
        return {"omega": self.omega, "gamma": self.gamma, "distance": self.distance}


def grasp_remarks(grasp: Grasp) -> str:
    """The pickup record's REMARKS (seed L2697): the grasp restated, with units.

    The emitter leaves a remark equal to this out of the program's PICKUP comment, which
    already states the grasp.
    """
    return (
        f"W = {math.degrees(grasp.omega):.1f} deg Grasp Angle = "
        f"{math.degrees(grasp.gamma):.1f} deg Grasp Distance = {100 * grasp.distance:.2f} cm"
    )


@dataclass(frozen=True, eq=False)
class GraspStrategy:
    """Pickup by grasping between the fingers (seed §4.1 "Grasp Strategy", L1895–1910).

    Openings in [m]; ``pickup_time`` is the expected pickup time [s] (the seed's pickup
    GOODNESS, L2697). ``grasp_determination`` is
    the pin-in-hand error block after ``center`` (None = NILTRANS, exactly held): ``(param,
    lo, hi)`` bounds [m, rad] of a perturbation in the pin frame. ``centering`` holds the
    certified bounds the openings and that block come from
    (:class:`synth.strategies.grasp.CenteringBounds`). ``joint_solution`` is the arm
    configuration at the grasp point and ``rating`` its grade (seed L2086–2100: |45° − θ5|,
    lower is better).
    """

    object: str
    grasp: Grasp
    approach_point: Destination
    grasp_point: Destination
    departure_point: Destination
    approach_opening: float
    grasp_opening: float
    pickup_time: float
    rating: float
    joint_solution: tuple[float, ...] = ()
    grasp_determination: Any = None
    preliminaries: tuple[str, ...] = ()
    remarks: str = ""
    centering: CenteringBounds | None = None
    approach_detour: tuple[Destination, ...] = ()
    """World via points of the hand before ``approach_point``, lifting the move from the park
    over what stands between (:mod:`synth.strategies.detour`); empty: a straight move."""

    def to_json(self) -> dict[str, Any]:
        """JSON form (SI)."""
        return {
            "object": self.object,
            **self.grasp.to_json(),
            "approach_detour": [d.to_json() for d in self.approach_detour],
            "approach_point": self.approach_point.to_json(),
            "grasp_point": self.grasp_point.to_json(),
            "departure_point": self.departure_point.to_json(),
            "approach_opening": self.approach_opening,
            "grasp_opening": self.grasp_opening,
            "pickup_time": self.pickup_time,
            "rating": self.rating,
            "remarks": self.remarks,
            "grasp_determination": None
            if self.grasp_determination is None
            else [list(b) for b in self.grasp_determination],
            "centering": None if self.centering is None else self.centering.to_json(),
        }


@dataclass(frozen=True)
class ErrorFootprint:
    """Pin-tip errors against the hole at the approach (seed §4.5, Fig. 4.1).

    A box with half-sides ``dx, dy`` [m] in the hole plane rotated by ``zeta`` [rad] about the
    hole axis, ``dz`` [m] along it, and the axis tilt ``dtheta`` [rad]. Values are the certified
    bounds the decisions use; ``first_order`` keeps the seed's linearised figures for display.
    """

    dx: float
    dy: float
    dz: float
    zeta: float
    dtheta: float
    first_order: dict[str, float] = field(default_factory=dict)

    @property
    def dr(self) -> float:
        """``Δr = max(Δx, Δy)`` (seed L2437)."""
        return max(self.dx, self.dy)

    def corners(self) -> NDArray[np.float64]:
        """The box's corners in the hole plane [m], as columns: ±dx × ±dy turned by ζ."""
        c, s = math.cos(self.zeta), math.sin(self.zeta)
        turn = np.array([[c, -s], [s, c]])
        return turn @ np.array(
            [[-self.dx, self.dx, self.dx, -self.dx],
             [-self.dy, -self.dy, self.dy, self.dy]]
        )  # fmt: skip

    def to_json(self) -> dict[str, Any]:
        """JSON form (SI)."""
        return {
            "dx": self.dx,
            "dy": self.dy,
            "dz": self.dz,
            "zeta": self.zeta,
            "dtheta": self.dtheta,
            "first_order": dict(self.first_order),
        }


@dataclass(frozen=True, eq=False)
class Tap:
    """A tap on the hole's surface to measure the hole along its axis (seed §4.5.2).

    ``offset`` [m] is the tapping place in the hole frame (z = 0 on the surface);
    ``place``/``via``/``target`` the destinations of the guarded move; ``dz_after`` [m] the
    certified Δz with the measurement added; ``time`` [s] its expected extra time.
    ``clearance`` [m] is the place's distance to the nearest hole or edge. Planner extras:
    ``dz_first_order`` [m] the seed's linearised corrected Δz, ``ring_radius`` [m] the radius of
    the search ring the place came from and ``ring`` its scored points ``(x, y, d)`` [m] in the
    surface frame (the table at L2345), ``measurement_bound`` [m] the largest |CORR| possible.
    """

    offset: tuple[float, float, float]
    surface: str
    clearance: float
    place: Destination
    via: Destination
    target: Destination
    dz_after: float
    time: float
    dz_first_order: float = math.nan
    ring_radius: float = math.nan
    ring: tuple[tuple[float, float, float], ...] = ()
    measurement_bound: float = math.nan

    def to_json(self) -> dict[str, Any]:
        """JSON form (SI)."""
        return {
            "offset": list(self.offset),
            "surface": self.surface,
            "clearance": self.clearance,
            "dz_after": self.dz_after,
            "dz_first_order": self.dz_first_order,
            "time": self.time,
            "ring_radius": self.ring_radius,
            "measurement_bound": self.measurement_bound,
        }


OffSurface = Literal["abort", "retract"]
"""A search move that reaches its target without a force has passed beside the surface: the
footprint (object pose errors) can reach past the edge of the face the hole is in (seed_4_8: BH1
is 0.60 cm from two edges of a box that may be 1.4 cm off). ``abort`` is the seed's listing
(L2762–2763, "EXPECTED A FORCE HERE"); ``retract`` backs the pin out along the hole axis to the
point's approach and tries the next point, since the hole may still lie further on."""


@dataclass(frozen=True)
class Search:
    """A spiral search over the error footprint (seed §4.8, L2740–2790).

    Rings of radius ``step, 2·step, …`` [m] up to ``rings·step``, points every ``step/r`` [rad]
    around each, kept when ``|x| ≤ dx`` and ``|y| ≤ dy`` [m]; offsets are turned by ``zeta``
    [rad] into the hole frame. ``expected_points`` counts the pattern points within
    ``dx/2, dy/2`` (seed L2470), ``time`` [s] their expected cost.
    """

    dx: float
    dy: float
    zeta: float
    step: float
    rings: int
    expected_points: int
    time: float
    off_surface: OffSurface = "retract"
    """What a search move that feels nothing does (see :data:`OffSurface`)."""
    first_off_surface: OffSurface = "abort"
    """What the first attempt does when it feels nothing: the seed's arrival abort (L2736),
    or, where the planner found that it may come down off the face
    (:func:`synth.strategies.beside.first_attempt_may_go_beside`) and the search retracts,
    back out to the approach point and search."""

    def to_json(self) -> dict[str, Any]:
        """JSON form (SI)."""
        return {
            "dx": self.dx,
            "dy": self.dy,
            "zeta": self.zeta,
            "step": self.step,
            "rings": self.rings,
            "expected_points": self.expected_points,
            "off_surface": self.off_surface,
            "first_off_surface": self.first_off_surface,
            "time": self.time,
        }


@dataclass(frozen=True, eq=False)
class PinInHoleStrategy:
    """A pin-in-hole strategy (seed §4.1 "Pin-in-Hole Strategy", L1848–1890).

    ``phi`` [rad] is the pin's rotation relative to the hole on insertion; ``dtry`` [m] how far
    into the hole the guarded move aims (d_f + 1 in); ``standoff`` [m] the approach height
    above the hole. ``success_threshold`` [m] is the ``DISTANCE_OFF`` test of the generated
    program and ``force_threshold`` [N] the guarded moves' stop force. Times in [s]:
    ``gross_time`` (pickup + transport: the seed's TTIME, printed as GOODNESS), ``fine_time``
    (tap + search: FINETIME) and :attr:`expected_time` = their sum (L1888);
    :attr:`pickup_time` and :attr:`transport_time` split ``gross_time`` (``docs/glossary.md``).

    After the insertion (seed L2839–2844): ``fingers`` is the AL name of the hand device that
    ``OPEN`` drives (``BHAND``; ``hand`` is the arm frame, ``BMANIP``); ``release_opening`` [m]
    the opening to let go (None: the pickup's approach opening, as the seed does) and
    ``retreat`` where the hand goes to get clear (None: 2 in back along its own z). Read them
    through :attr:`let_go_opening` and :attr:`get_clear`.
    """

    pin: str
    hole: str
    hand: str
    pickup: GraspStrategy
    phi: float
    dtry: float
    standoff: float
    approach: Destination
    destination: Destination
    target: Destination
    d_f: float
    d_s: float
    dr_ok: float
    success_threshold: float
    force_threshold: float
    gross_time: float
    fine_time: float = 0.0
    release_time: float = 0.0
    """[s] the let-go and get-clear after the insertion (OPEN and the move back, L2839–2844),
    which the seed's expected time leaves out (:func:`~synth.strategies.approach.release_time`)."""
    errors: ErrorFootprint | None = None
    tap: Tap | None = None
    search: Search | None = None
    preliminaries: tuple[str, ...] = ()
    name: str = ""
    fingers: str = "BHAND"
    release_opening: float | None = None
    retreat: Destination | None = None
    decisions: tuple[str, ...] = ()
    """The planner's reasons in words: why a tap and a search, or why not (seed §4.8)."""
    approach_vias: tuple[Destination, ...] = ()
    """Via points along the hole axis between ``approach`` and ``target``, in order: they bound
    the bow of the joint-interpolated approach (:mod:`synth.strategies.bow`)."""
    bow: float = 0.0
    """[m] how far the approach through ``approach_vias`` bows off the hole axis (measured on
    the arm model, added to the footprint)."""
    lead: float | None = None
    """[m] the parts' geometric lead, chamfer + hole radius − tip radius: what the replay
    captures within (:func:`synth.models.insertion.exceeds_lead` compares ``dr_ok`` with it);
    None where it was not derived."""
    transport_detour: tuple[Destination, ...] = ()
    """World via points of the pin after the departure point, lifting the transport over what
    stands between (:mod:`synth.strategies.detour`); empty: a straight move."""
    dtheta_ok: float | None = None
    """[rad] the tilt the insertion accommodates as refined: the task's Δθ_ok, or the wedging
    limit when that is tighter (L1961); None before refinement."""

    @property
    def expected_time(self) -> float:
        """Expected total time [s]: ``gross_time + fine_time`` (seed L1888) ``+ release_time``.

        Without the release, programs that need no search replayed about 1.0 s slower than
        their expected time (a task hunt's measurement: OPEN's 50 jiffies and the 2 in back).
        """
        return self.gross_time + self.fine_time + self.release_time

    @property
    def pickup_time(self) -> float:
        """Expected pickup time [s]: open, approach and grasp, centre, lift."""
        return self.pickup.pickup_time

    @property
    def transport_time(self) -> float:
        """Expected time [s] carrying the pin from the pickup to above the hole."""
        return self.gross_time - self.pickup.pickup_time

    @property
    def dz_at_test(self) -> float | None:
        """Δz [m] the success test is made with (see :func:`~.refine.success_threshold`).

        The footprint's, or the tap's once it has measured the face; None without a footprint.
        """
        if self.errors is None:
            return None
        return self.errors.dz if self.tap is None else self.tap.dz_after

    @property
    def let_go_opening(self) -> float:
        """Opening [m] to let go of the pin (seed L2840: ``OPEN BHAND TO 2.98``).

        ``release_opening`` when set, else the pickup's approach opening, as the seed does.
        """
        if self.release_opening is not None:
            return self.release_opening
        return self.pickup.approach_opening

    @property
    def get_clear(self) -> Destination:
        """Where the hand goes after letting go (seed L2844).

        ``retreat`` when set, else the seed's ``BMANIP*TRANS(NILROTN,VECTOR(0,0,-5.08))``:
        the hand 2 in [0.0508 m] back along its own approach axis, relative to where it is.
        """
        if self.retreat is not None:
            return self.retreat
        back = pin.SE3(np.eye(3), np.array([0.0, 0.0, -RETREAT_DISTANCE]))
        return Destination("get clear", self.hand, self.hand, back)

    @property
    def refined(self) -> bool:
        """True once the accuracy refinements of §4.5 have been applied."""
        return self.errors is not None

    def to_json(self) -> dict[str, Any]:
        """The ``strategy`` object of ``synth plan --json`` (SI units)."""
        errors = self.errors
        return {
            "name": self.name,
            "pin": self.pin,
            "hole": self.hole,
            "grasp": self.pickup.grasp.to_json(),
            "pickup": self.pickup.to_json(),
            "phi": self.phi,
            "dtry": self.dtry,
            "standoff": self.standoff,
            # the insertion as planned: Δr_ok may be the lead's, Δθ_ok the wedging limit's
            "d_f": self.d_f,
            "d_s": self.d_s,
            "dr_ok": self.dr_ok,
            "dtheta_ok": self.dtheta_ok,
            "lead": self.lead,
            "preliminaries": list(self.preliminaries),
            "transport_detour": [v.to_json() for v in self.transport_detour],
            "approach_vias": [v.to_json() for v in self.approach_vias],
            "bow": self.bow,
            "tap": None if self.tap is None else self.tap.to_json(),
            "search": None if self.search is None else self.search.to_json(),
            "errors": None
            if errors is None
            else {
                "dx": errors.dx,
                "dy": errors.dy,
                "dz": errors.dz,
                "zeta": errors.zeta,
                "dtheta": errors.dtheta,
            },
            "time": time_json(self),
            "success_threshold": self.success_threshold,
            "force_threshold": self.force_threshold,
            "let_go_opening": self.let_go_opening,
            "get_clear": self.get_clear.to_json(),
            "decisions": list(self.decisions),
        }


def time_json(s: PinInHoleStrategy) -> dict[str, float]:
    """A strategy's expected times [s] under the names the text uses (``docs/glossary.md``).

    ``expected_time`` = ``pickup_time`` + ``transport_time`` + ``fine_time`` +
    ``release_time``;
    ``gross_time`` = ``pickup_time`` + ``transport_time`` (the candidates' ranking before
    refinement).
    """
    return {
        "pickup_time": s.pickup_time,
        "transport_time": s.transport_time,
        "gross_time": s.gross_time,
        "fine_time": s.fine_time,
        "release_time": s.release_time,
        "expected_time": s.expected_time,
    }


@dataclass(frozen=True)
class Rejection:
    """A candidate the planner dropped, and why (shown by ``synth plan``).

    ``cause`` is one of :data:`synth.strategies.causes.CAUSES` (``None``: read from the reason
    by :func:`~synth.strategies.causes.classify`); ``stage`` the planning stage that dropped it
    (``pickup``, ``approach``, ``refine``, ``proof``; the planner fills it in).
    """

    candidate: str
    reason: str
    cause: str | None = None
    stage: str | None = None
    refuted: str | None = None
    """The planner's belief a failed proof refuted: ``dr_ok`` when a trial missed the hole (its
    pin was not captured where Δr_ok said it would be), else None."""
    proven: bool = False
    """The proof passed, yet one of its trials refuted ``refuted``: the program is written only
    if nothing planned without that belief is proven (:func:`~synth.strategies.planner.plan_task`
    keeps it as the fallback)."""

    @property
    def kind(self) -> str:
        """The cause: the one given, or the one the reason's wording names."""
        return self.cause if self.cause is not None else classify(self.reason)

    def to_json(self) -> dict[str, str | None]:
        """JSON form."""
        return {
            "candidate": self.candidate,
            "reason": self.reason,
            "cause": self.kind,
            "stage": self.stage,
        }


@dataclass(frozen=True, eq=False)
class PlanResult:
    """Outcome of planning: the chosen strategy, the candidates and the rejections.

    ``refined`` counts the candidates refined (§4.5) before selection stopped; ``mode`` is
    ``best-first`` or ``exhaustive``; ``minimum_refinement_cost`` [s] the cutoff's lower bound on
    fine-motion time (L2459); ``planning_time`` [s] wall time; ``counters`` the IK, motion-time,
    bound and LP calls.
    """

    strategy: PinInHoleStrategy
    candidates: tuple[PinInHoleStrategy, ...]
    rejected: tuple[Rejection, ...]
    refined: int
    planning_time: float
    counters: dict[str, int] = field(default_factory=dict)
    mode: str = "best-first"
    minimum_refinement_cost: float = 0.0

    def to_json(self) -> dict[str, Any]:
        """The whole ``synth plan --json`` document (without the program text)."""
        return {
            "strategy": self.strategy.to_json(),
            "candidates": [
                {
                    "name": c.name,
                    "grasp": c.pickup.grasp.to_json(),
                    "phi": c.phi,
                    "refined": c.refined,
                    "time": time_json(c),
                    "tap": c.tap is not None,
                    "search": c.search is not None,
                }
                for c in self.candidates
            ],
            "rejected": [r.to_json() for r in self.rejected],
            "refined": self.refined,
            "mode": self.mode,
            "minimum_refinement_cost": self.minimum_refinement_cost,
            "planning_time": self.planning_time,
            "counters": dict(self.counters),
        }


RETREAT_DISTANCE = 2 * INCH
"""How far the hand backs off after letting go when the record names no retreat [m] (L2844)."""
