"""The seed's two chosen strategies of §4.8 as hand-built records (no planner involved).

The codegen tests emit them and compare with the seed's listings. Every figure is the one the
seed prints (seeds/000_1457622cbb9a2614.txt):

- ``seed_4_8`` — strategy 130523, PHL SPEC L2690–2710 and its program L2715–2781: ω = 315°,
  γ = 180°, d = 3.54 cm; hand at PIN1*TRANS(ROTN((.924, .383, .00106), 180°), (0, 0, 3.54) cm)
  via (0, 0, 8.62) cm (the ".001" is 0.00106, footnote 21, L2789); approach opening 2.98 cm,
  grasp opening .185 cm; departure PIN1*(0, 0, 6.79) cm; φ = 90°, standoff 2.54 cm,
  dtry = 4.25 cm, d_f = 1.71 cm; footprint 1.58 × 1.15 cm at ζ = 1.05 rad, Δz = .127 cm;
  Δr_ok = .762 cm; threshold .169 cm; 8 oz; search rings .572 cm apart out to 1.72 cm (three
  rings); estimated time 6.14 s with FINE TIME .688 s.
- ``seed_4_8_tap`` — strategy 134356, the variation's program L2804–2844: ω = 98°, γ = 135°,
  d = 3.54 cm; hand at PIN1*TRANS(ROTN((.679, .679, .281), 149°), (0, 0, 3.54) cm) via
  (−3.59, 0, 7.13) cm; tap at (−1.21, −.002, 0) cm in BH1 from 5.08 cm above to 5.08 cm below;
  footprint .243 × .226 cm at ζ = .524 rad, Δz = .188 cm; threshold .239 cm; no search;
  estimated time 6.67 s.

Figures the seed does not print (tilt bound, grasp rating, pickup goodness of the variation,
the split of the total time, the search's expected point count) are filled with stated
stand-ins; code generation prints none of them.

Note the seed's printed hand rotation is not ``rot(ẑ, ω)·rot(x̂, γ)`` of the printed ω (for
ω = 315°, γ = 180° that is a half turn about (.924, −.383, 0)): the destinations below are the
printed ones, because they are what the program moves to.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from synth.strategies.records import (
    Destination,
    ErrorFootprint,
    Grasp,
    GraspStrategy,
    PinInHoleStrategy,
    Search,
    Tap,
)
from synth.units import CM, DEG, OZ

__all__ = ["STRATEGIES", "seed_4_8", "seed_4_8_tap"]


def _rot(axis: tuple[float, float, float], angle: float) -> np.ndarray:
    a = np.asarray(axis, dtype=float)
    return np.asarray(pin.exp3(a / np.linalg.norm(a) * angle))


def _xf(rotation: np.ndarray, cm: tuple[float, float, float]) -> pin.SE3:
    return pin.SE3(rotation, np.asarray(cm, dtype=float) * CM)


_NIL = np.eye(3)
_RZ90 = _rot((0, 0, 1), 90 * DEG)


def _insertion(label_base: str = "BH1") -> tuple[Destination, Destination, Destination]:
    """Approach 2.54 cm above BH1, seated at d_f = 1.71 cm, aim at dtry = 4.25 cm (L2733–2737)."""
    return (
        Destination("approach", "PIN1", label_base, _xf(_RZ90, (0, 0, 2.54))),
        Destination("destination", "PIN1", label_base, _xf(_RZ90, (0, 0, -1.71))),
        Destination("target", "PIN1", label_base, _xf(_RZ90, (0, 0, -4.25))),
    )


def seed_4_8() -> PinInHoleStrategy:
    """Strategy 130523 (search, no tap), L2690–2781."""
    hand_in_pin = _rot((0.924, 0.383, 0.00106), 180 * DEG)
    pickup = GraspStrategy(
        object="PIN1",
        grasp=Grasp(omega=315 * DEG, gamma=180 * DEG, distance=3.54 * CM),
        approach_point=Destination("approach", "BMANIP", "PIN1", _xf(hand_in_pin, (0, 0, 8.62))),
        grasp_point=Destination("grasp", "BMANIP", "PIN1", _xf(hand_in_pin, (0, 0, 3.54))),
        departure_point=Destination("departure", "PIN1", "PIN1", _xf(_NIL, (0, 0, 6.79))),
        approach_opening=2.98 * CM,
        grasp_opening=0.185 * CM,
        pickup_time=4.16,  # PICKUP GOODNESS, L2697
        rating=0.0,  # not printed
    )
    approach, destination, target = _insertion()
    return PinInHoleStrategy(
        pin="PIN1",
        hole="BH1",
        hand="BMANIP",
        pickup=pickup,
        phi=90 * DEG,
        dtry=4.25 * CM,
        standoff=2.54 * CM,
        approach=approach,
        destination=destination,
        target=target,
        d_f=1.71 * CM,
        d_s=0.0,
        dr_ok=0.762 * CM,
        success_threshold=0.169 * CM,
        force_threshold=8 * OZ,
        gross_time=6.14 - 0.688,  # GOODNESS 6.14 less FINE TIME .688, L2703–2705
        fine_time=0.688,
        errors=ErrorFootprint(
            dx=1.58 * CM,
            dy=1.15 * CM,
            dz=0.127 * CM,
            zeta=1.05,
            dtheta=0.0,  # tilt not printed
        ),
        search=Search(
            dx=1.58 * CM,
            dy=1.15 * CM,
            zeta=1.05,
            step=0.572 * CM,
            rings=3,
            expected_points=7,  # ring points within 0.79 × 0.575 cm (L2470); not printed
            time=0.688,
            off_surface="abort",  # L2762: the listing aborts where nothing is felt
        ),
        name="130523",
    )


def seed_4_8_tap() -> PinInHoleStrategy:
    """Strategy 134356 (tap, no search), L2804–2844."""
    hand_in_pin = _rot((0.679, 0.679, 0.281), 149 * DEG)
    pickup = GraspStrategy(
        object="PIN1",
        grasp=Grasp(omega=98 * DEG, gamma=135 * DEG, distance=3.54 * CM),
        approach_point=Destination(
            "approach", "BMANIP", "PIN1", _xf(hand_in_pin, (-3.59, 0, 7.13))
        ),
        grasp_point=Destination("grasp", "BMANIP", "PIN1", _xf(hand_in_pin, (0, 0, 3.54))),
        departure_point=Destination("departure", "PIN1", "PIN1", _xf(_NIL, (0, 0, 6.79))),
        approach_opening=2.98 * CM,
        grasp_opening=0.185 * CM,
        pickup_time=4.16,  # not printed for the variation; the search version's figure
        rating=0.0,
    )
    approach, destination, target = _insertion()
    tap_place = (-1.21, -0.002, 0.0)
    return PinInHoleStrategy(
        pin="PIN1",
        hole="BH1",
        hand="BMANIP",
        pickup=pickup,
        phi=90 * DEG,
        dtry=4.25 * CM,
        standoff=2.54 * CM,
        approach=approach,
        destination=destination,
        target=target,
        d_f=1.71 * CM,
        d_s=0.0,
        dr_ok=0.762 * CM,
        success_threshold=0.239 * CM,
        force_threshold=8 * OZ,
        gross_time=6.67 - 1.2,  # ESTIMATED TIME 6.67 (L2806); tapping ≈ 1.2 s (§8 of the notes)
        fine_time=1.2,
        errors=ErrorFootprint(dx=0.243 * CM, dy=0.226 * CM, dz=0.188 * CM, zeta=0.524, dtheta=0.0),
        tap=Tap(
            offset=(tap_place[0] * CM, tap_place[1] * CM, 0.0),
            surface="box_top",
            clearance=5.08 * CM,
            place=Destination("tap place", "PIN1", "BH1", _xf(_NIL, tap_place)),
            via=Destination("tap start", "PIN1", "BH1", _xf(_NIL, (-1.21, -0.002, 5.08))),
            target=Destination("tap target", "PIN1", "BH1", _xf(_NIL, (-1.21, -0.002, -5.08))),
            dz_after=0.188 * CM,
            time=1.2,
        ),
        name="134356",
    )


STRATEGIES = {"seed_4_8": seed_4_8, "seed_4_8_tap": seed_4_8_tap}
"""Task name (fixtures/tasks/<name>.yaml) → its hand-built strategy."""
