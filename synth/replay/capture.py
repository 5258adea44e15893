"""Where a pin's tip is relative to a hole, whether the hole captures it, and where it seats.

Pure geometry of the true parts, independent of the planner's insertion parameters (Δr_ok,
Δθ_ok of the task are what the *planner* believes; the replay measures the parts instead).

**Tip placement.** With the hole's mouth frame M (z out of the hole) and the pin frame P (origin
at the tip centre, z from the tip to the head), ``M⁻¹ P`` gives the tip centre's distance from
the hole axis (``lateral``), its height above the mouth plane (``axial``, negative inside) and
the angle between the two axes (``tilt``; a pin going in tip first has its z along the hole's z).

**Capture.** A 45° chamfer of width w around a bore of radius r has a mouth of radius
r_m = r + w. A tip of radius a that arrives at the mouth plane (or touches the chamfer) with its
whole tip circle inside the mouth, ``lateral + a ≤ r_m``, meets only the chamfer or the bore,
never the flat surface, and the chamfer slides it onto the axis. The tilt the geometry admits is
that of a pin pivoting on the mouth's rim with its tip circle still landing inside it:

    θ_max = atan((r_m − a) / (h + w)),   h = the pin's tip taper length.

Only the tip end is modelled: a pin arriving head first (turned over) is never captured, which
is why the planner refuses such insertions. A captured pin may still wedge at its two-point
contact (:mod:`synth.replay.wedging`, decided by :mod:`synth.replay.contact`).

**Seat.** A captured pin slides along the hole axis until it is stopped: by the hole's bottom
when its shaft fits the bore (depth = hole depth, or the pin's length if the hole is deeper),
otherwise where its taper wedges in the bore or its tip in the chamfer.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from synth.models.workcell import HoleSite, PinModel

__all__ = [
    "TipPlacement",
    "admissible_tilt",
    "captures",
    "inserted_depth",
    "seat_depth",
    "seated_pose",
    "tip_placement",
]


@dataclass(frozen=True)
class TipPlacement:
    """The pin's tip relative to a hole: ``lateral`` [m], ``axial`` [m], ``tilt`` [rad]."""

    lateral: float
    axial: float
    tilt: float


def tip_placement(hole: HoleSite, pin_pose: pin.SE3) -> TipPlacement:
    """Tip centre and pin axis of a pin at world pose ``pin_pose`` in the hole's mouth frame."""
    local = hole.world_from_hole.actInv(pin_pose)
    c = local.translation
    cos_tilt = min(max(float(local.rotation[2, 2]), -1.0), 1.0)
    return TipPlacement(float(math.hypot(c[0], c[1])), float(c[2]), math.acos(cos_tilt))


def admissible_tilt(hole: HoleSite, pin_model: PinModel) -> float:
    """θ_max = atan((r_m − a) / (h + w)) [rad] (module docstring)."""
    lead = hole.mouth_radius - pin_model.tip_radius
    height = pin_model.shape.tip_taper_length + hole.chamfer
    if lead <= 0.0:
        return 0.0
    return math.atan2(lead, height) if height > 0.0 else math.pi / 2


def captures(hole: HoleSite, pin_model: PinModel, placement: TipPlacement) -> bool:
    """Whether the tip circle lies inside the mouth and the tilt is admissible."""
    inside = placement.lateral + pin_model.tip_radius * math.cos(placement.tilt)
    return inside <= hole.mouth_radius and placement.tilt <= admissible_tilt(hole, pin_model)


def seat_depth(hole: HoleSite, pin_model: PinModel) -> float:
    """Depth [m] of the tip below the mouth when the captured pin is stopped (module docstring)."""
    r, w = hole.radius, hole.chamfer
    a, b, h = pin_model.tip_radius, pin_model.radius, pin_model.shape.tip_taper_length
    if b <= r:
        return min(hole.depth, pin_model.length)
    if a < r and h > 0.0:
        # the taper section of radius r enters the bore's top (depth w) and wedges there
        z_wedge = h * (r - a) / (b - a)
        return min(hole.depth, w + z_wedge)
    if a < r + w:
        # the tip edge rests on the 45° cone where its radius equals a
        return w - (a - r)
    return 0.0


def seated_pose(hole: HoleSite, depth: float, pin_pose: pin.SE3) -> pin.SE3:
    """The pin on the hole axis with its tip ``depth`` [m] below the mouth, its spin kept.

    The spin is the angle of the pin's x axis projected on the mouth plane (0 if the pin's x
    axis is along the hole axis).
    """
    local = hole.world_from_hole.actInv(pin_pose).rotation
    x = local[:, 0]
    spin = math.atan2(x[1], x[0]) if math.hypot(x[0], x[1]) > 1e-9 else 0.0
    placement = pin.SE3(pin.utils.rotate("z", spin), np.array([0.0, 0.0, -depth]))
    return hole.world_from_hole * placement


def inserted_depth(
    hole: HoleSite, pin_model: PinModel, pin_pose: pin.SE3, tolerance: float = 1e-6
) -> float | None:
    """The tip's depth [m] if the pin stands in the hole's bore (on its axis), else None.

    In the bore means: tip below the mouth plane, axis within the radial clearance (plus
    ``tolerance`` [m]) of the hole's axis, and the two axes parallel within ``tolerance`` [rad].
    """
    placement = tip_placement(hole, pin_pose)
    clearance = max(hole.radius - pin_model.radius, 0.0)
    if (
        placement.axial < 0.0
        and placement.lateral <= clearance + tolerance
        and placement.tilt <= tolerance
    ):
        return -placement.axial
    return None
