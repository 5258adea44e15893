"""The two-finger hand as collision bodies: a palm and two finger plates (seed L1984).

Hand frame (AL's hand frame, Paul's T6): origin midway between the finger pads, z the approach
vector out of the fingers, fingers closing along x. The seed's grasp frame
``rot(ẑ, ω)·rot(x̂, γ)`` (L2000) keeps the pin axis in the hand's y–z plane, which is why the pads
face along x. With opening w [m] (the gap between the pads) and finger thickness t:

* finger ``finger_left`` / ``finger_right``: a box t × 2r_p × (L_f + r_p) whose inner face is at
  x = ∓w/2, reaching from the palm face (z = −L_f) to one pad radius past the pad centres;
* ``palm``: a box of ``palm_size`` behind the fingers, z ∈ [−L_f − h_palm, −L_f].
"""

from __future__ import annotations

from typing import Literal

import coal
import numpy as np
import pinocchio as pin

from synth.models.arm.bodies import Body
from synth.models.manipulator import HandSpec

FINGERS: tuple[str, str] = ("finger_left", "finger_right")
PALM = "palm"
HAND_BODIES: tuple[str, ...] = (PALM, *FINGERS)


def finger_placement(hand: HandSpec, side: Literal[-1, 1], opening: float) -> pin.SE3:
    """Pose of one finger box in the hand frame: centre (s·(w/2 + t/2), 0, (r_p − L_f)/2) [m]."""
    x = side * (opening / 2 + hand.finger_thickness / 2)
    z = (hand.finger_pad_radius - hand.finger_length) / 2
    return pin.SE3(np.eye(3), np.array([x, 0.0, z]))


def palm_top(hand: HandSpec) -> float:
    """Distance [m] from the hand origin back to the palm's rear face: L_f + h_palm."""
    return hand.finger_length + hand.palm_size[2]


def hand_bodies(
    hand: HandSpec, joint: int, link: str, joint_from_hand: pin.SE3, opening: float
) -> list[Body]:
    """Palm and finger bodies carried by ``joint``, the hand frame at ``joint_from_hand``."""
    if not 0.0 <= opening <= hand.max_opening + 1e-12:
        raise ValueError(f"opening {opening} m outside [0, {hand.max_opening}] m")
    finger = (
        hand.finger_thickness,
        2 * hand.finger_pad_radius,
        hand.finger_length + hand.finger_pad_radius,
    )
    palm_centre = np.array([0.0, 0.0, -hand.finger_length - hand.palm_size[2] / 2])
    bodies = [
        Body(
            PALM,
            joint,
            link,
            joint_from_hand * pin.SE3(np.eye(3), palm_centre),
            coal.Box(*hand.palm_size),
            "hand",
        )
    ]
    for name, side in zip(FINGERS, (-1, 1), strict=True):
        placement = joint_from_hand * finger_placement(hand, side, opening)  # type: ignore[arg-type]
        bodies.append(Body(name, joint, link, placement, coal.Box(*finger), "hand"))
    return bodies
