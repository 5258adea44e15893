"""Planner options: every constant of seed ch. IV §4.3–4.6 in one frozen record, SI units.

The seed calls most of these numbers "arbitrary" (L2139, L2186) or "current" (L2038, L2289);
they are parameters here, with the seed's values as defaults and the line each comes from.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from synth.models.arm import JIFFY
from synth.strategies.records import OffSurface
from synth.units import DEG, INCH, OZ

"""[m] one inch."""
"""[rad] one degree."""

"""[N] the weight of one ounce (AL's ``OZ`` as a force)."""

TimingRule = Literal["quintic", "ruckig", "seed"]
HandErrorModel = Literal["independent", "repeatable"]


@dataclass(frozen=True)
class PlanOptions:
    """Constants of the pin-in-hole planner (seed §4.3–4.6); lengths [m], angles [rad], [s]."""

    kappa: float = 0.1 * INCH
    """κ [m]: extra finger clearance in the grasp-distance limits (L2038)."""
    short_interval: float = 2.5 * INCH
    """[m] a d interval shorter than this gets its midpoint only (L2050)."""
    distance_offset: float = 0.6 * INCH
    """[m] d₁ = d_max − 0.6 in, d₂ = d_min + 0.6 in on a long interval (L2056–2058)."""
    same_end_gammas: tuple[float, ...] = (180 * DEG, 135 * DEG, 100 * DEG)
    """γ values [rad] when the same pin end goes into both holes (L2064–2068)."""
    turn_over_gamma: float = 90 * DEG
    """γ [rad] when the pin is turned over between the holes (L2078)."""
    omega_step: float = 45 * DEG
    """[rad] ω is tried in these increments (L2082)."""
    keep_omegas: int = 3
    """Best-rated ω values kept per (γ, d) (L2122); ``try_harder`` keeps all."""
    phi_step: float = 45 * DEG
    """[rad] φ candidates 0, 45°, …, 315° (the table at L2170–2180)."""
    grasp_approach_distance: float = 2 * INCH
    """[m] the grasp's approach point backs off along the hand's approach vector (PHL SPEC
    printouts L2609–2612: VECTOR(−3.59, 0, 7.13) = (0, 0, 3.54) − 5.08·ẑ_hand)."""
    departure_lift: float = 2 * INCH
    """[m] the departure point lifts the pin tip this far above its start hole (L2128)."""
    approach_opening_extra: float = 1 * INCH
    """[m] approach opening = pin diameter + this (L2139)."""
    closure_margin: float = 0.1 * INCH
    """[m] grasp (closure) threshold = pin diameter − this (L2139)."""
    dtry_extra: float = 1 * INCH
    """[m] dtry = d_f + this (L2188)."""
    standoff: float = 1 * INCH
    """[m] height of the approach point above the hole (L2190)."""
    force_threshold: float = 8 * OZ
    """[N] stop force of the guarded moves: ``on force(pin*zhat)>8*oz`` (L2148; the OCR reads
    "8*DZ" at L2735)."""
    tau: float = 0.75
    """τ [1]: |Δz| ≤ τ·(d_f − d_s) is needed to tell an insertion from a miss (L2289)."""
    reading_floor: float = 0.01 * INCH
    """[m] the least margin of the success test over Δz: the arm's reading is given in 0.01 in
    (seed L3385, L3697), so a test within that of the seated reading may reject a seated pin.
    The threshold is max(Δz/τ, Δz + this) (:func:`~synth.strategies.refine.success_threshold`):
    Δz/τ alone is 0 in a cell known exactly, a test nothing passes."""
    tap_ring_min: float = 0.3 * INCH
    """[m] Δr_td = max(0.3 in, Δx, Δy): ring spacing of the tapping-place search (L2304)."""
    tap_travel: float = 2 * INCH
    """[m] the tap starts this far above the nominal surface and aims this far below (L2852)."""
    search_step_fraction: float = 0.75
    """Search ring spacing = this · Δr_ok (L2743: ``R = .572; ! 0.75*DROK``)."""
    search_off_surface: OffSurface = "retract"
    """A search point where nothing is felt: ``retract`` and try the next point, or ``abort``
    as the seed's listing does (L2762); see :data:`synth.strategies.records.OffSurface`."""
    open_time: float = 50 * JIFFY
    """[s] OPEN BHAND (seed App. 2, L3854: 50 jiffies)."""
    center_time: float = 50 * JIFFY
    """[s] CENTER BMANIP (seed App. 2, L3857: 50 jiffies)."""
    timing_rule: TimingRule = "quintic"
    """Motion-time rule of :func:`synth.models.arm.motion_time` (``seed``: L3846)."""
    tap_hand_errors: HandErrorModel = "independent"
    """How the hand errors at the tap and at the insertion relate: ``independent`` blocks
    (conservative) or one ``repeatable`` block (a calibration error that the tap cancels)."""
    try_harder: bool = False
    """Keep every grasp orientation ω with an arm solution, not the best three (L2122)."""
    exhaustive: bool = False
    """Refine every candidate instead of stopping at the best-first cutoff (L2463)."""
    at_lead: bool = False
    """Plan with Δr_ok and Δθ_ok at the parts' geometric lead when the task's Δr_ok is wider
    (:func:`synth.models.insertion.at_lead`): set for a sequence once a proof trial missed."""


def hand_openings(diameter: float, options: PlanOptions) -> tuple[float, float]:
    """``(approach, grasp)`` openings [m] (L2139).

    Approach: 1 in + the pin diameter at the grasp point. Grasp (the ``center`` closure
    threshold): the diameter − 0.1 in, but at least a quarter of the diameter. Fingers closing
    on the pin stop at its diameter and on nothing close past it, so any threshold between 0
    and the diameter tells the two apart; the seed's margin alone went to 0 at a 0.1 in pin
    and below it negative (a 2 mm dowel was refused with "grasp_opening: expected a positive
    number"). The seed's own pin (0.44 cm at the grasp point) keeps its 0.185 cm.
    """
    grasp = max(diameter - options.closure_margin, 0.25 * diameter)
    return diameter + options.approach_opening_extra, grasp
