"""A held pin sliding along a surface it grazed: the arm yields until the path clears, or jams.

The grazing contact that starts a slide is found by :mod:`synth.replay.contact`
(:func:`~synth.replay.contact.first_contact`); the walk (:mod:`synth.replay.walk`) decides a
push shallower than ``slide_angle`` slides.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from synth.models.arm.collision import Obstacle
from synth.models.workcell import PinModel
from synth.replay.contact import PinGeometry, Target
from synth.replay.motion import PoseAt

__all__ = ["ScrapeEnd", "scrape"]


@dataclass(frozen=True)
class ScrapeEnd:
    """How a slide ends: at ``s``, ``free``, ``jam`` or at the path's ``end``.

    ``free``: the path clears the obstacle; ``jam``: the arm would have to yield more than the
    compliance; ``deflection`` [m]: how far it yields there.
    """

    s: float
    kind: Literal["free", "jam", "end"]
    deflection: float


def scrape(
    pin_model: PinModel,
    pose_at: PoseAt,
    speed: float,
    obstacle: Obstacle,
    normal: NDArray[np.float64],
    pin_point: NDArray[np.float64],
    origin: NDArray[np.float64],
    *,
    start: float,
    end: float = 1.0,
    compliance: float = 0.01,
    clearance: float = 2e-5,
    step: float = 2e-4,
) -> ScrapeEnd:
    """Follow a pin sliding along ``obstacle`` from ``start`` until its path clears it.

    A pin pushed along a surface at a shallow angle slides: the arm yields along the surface
    normal n by the depth the commanded pin would reach into the obstacle, measured at the
    pin's contact point x (``pin_point``, pin frame) from where it touched (``origin``, world):
    δ(s) = −n·(P(s)x − x₀). The slide ends where the commanded pin no longer touches the
    obstacle (``free``), or jams where δ exceeds ``compliance`` [m]. The path is marched in
    steps that move the pin at most ``step`` [m].
    """
    pin_ = PinGeometry(pin_model)
    target = Target(obstacle)
    ds = step / speed if speed > 0.0 else 1.0
    s = start
    while s < end:
        s = min(end, s + ds)
        pose = pose_at(s)
        deflection = -float(normal @ (pose.act(pin_point) - origin))
        if deflection > compliance:
            return ScrapeEnd(s, "jam", deflection)
        if pin_.distance(pose, target, exact=True)[0] > clearance:
            return ScrapeEnd(s, "free", max(deflection, 0.0))
    return ScrapeEnd(end, "end", 0.0)
