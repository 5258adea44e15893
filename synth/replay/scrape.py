"""A held pin sliding along a surface it grazed: the arm yields until the path clears, or jams.

The grazing contact that starts a slide is found by :mod:`synth.replay.contact`
(:func:`~synth.replay.contact.first_contact`); the walk (:mod:`synth.replay.walk`) decides a
push shallower than ``slide_angle`` slides. The yield is :meth:`~synth.replay.motion.Slide.
deflection`'s; the pin, shifted by it, may meet another solid on the way (a pin lowered along a
box's wall meets the table): a contact the wrist feels.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from synth.models.arm.collision import Obstacle
from synth.models.workcell import PinModel
from synth.replay.contact import PinGeometry, Target
from synth.replay.motion import PoseAt, Slide

__all__ = ["ScrapeEnd", "scrape"]


@dataclass(frozen=True)
class ScrapeEnd:
    """How a slide ends: at ``s``, ``free``, ``jam``, ``touch`` or at the path's ``end``.

    ``free``: the path clears the obstacle; ``jam``: the arm would have to yield more than the
    compliance; ``touch``: the sliding pin meets ``touched`` (another solid) at ``point`` (world
    [m]); ``deflection`` [m]: how far the arm yields there.
    """

    s: float
    kind: Literal["free", "jam", "touch", "end"]
    deflection: float
    touched: Obstacle | None = None
    point: NDArray[np.float64] | None = None


def scrape(
    pin_model: PinModel,
    pose_at: PoseAt,
    speed: float,
    slide: Slide,
    others: Sequence[Obstacle],
    *,
    start: float,
    end: float = 1.0,
    compliance: float = 0.01,
    clearance: float = 2e-5,
    step: float = 2e-4,
) -> ScrapeEnd:
    """Follow a pin sliding along ``slide.obstacle`` from ``start`` until its path clears it.

    A pin pushed along a surface at a shallow angle slides: the arm yields along the surface
    normal n by δ(s), :meth:`~synth.replay.motion.Slide.deflection` of the commanded pose P(s).
    The slide ends where the commanded pin no longer touches the obstacle (``free``), jams where
    δ exceeds ``compliance`` [m], or stops where the pin as it truly is, P(s) moved by δ(s)·n,
    comes within ``clearance`` of one of ``others`` (``touch``). The path is marched in steps
    that move the commanded pin at most ``step`` [m]; the true pin moves at most ``step`` + |Δδ|
    a step, so another solid is measured again only once that sum since its last measurement
    reaches its gap less the clearance (a conservative advancement).
    """
    pin_ = PinGeometry(pin_model)
    target = Target(slide.obstacle)
    near = [Target(o) for o in others]
    ds = step / speed if speed > 0.0 else 1.0
    s = start
    last = slide.deflection(pose_at(s))
    gaps = np.array([pin_.gap(slide.yielded(pose_at(s), last), t, exact=True) for t in near])
    moved = np.zeros(len(near))
    while s < end:
        before, s = s, min(end, s + ds)
        pose = pose_at(s)
        deflection = slide.deflection(pose)
        if deflection > compliance:
            return ScrapeEnd(s, "jam", deflection)
        moved += step + abs(deflection - last)
        last = deflection
        for k in np.flatnonzero(moved >= gaps - clearance).tolist():
            gap = pin_.gap(slide.yielded(pose, deflection), near[k], exact=True)
            if gap <= clearance:
                return _touch(pin_, pose_at, slide, near[k], before, s, clearance)
            gaps[k], moved[k] = gap, 0.0
        if pin_.distance(pose, target, exact=True)[0] > clearance:
            return ScrapeEnd(s, "free", deflection)
    return ScrapeEnd(end, "end", 0.0)


def _touch(
    pin_: PinGeometry,
    pose_at: PoseAt,
    slide: Slide,
    target: Target,
    apart: float,
    touching: float,
    clearance: float,
) -> ScrapeEnd:
    """The sliding pin's stop on ``target``: where its gap first reaches the clearance.

    The gap is above ``clearance`` at ``apart`` (the advancement's bound) and not at
    ``touching``; halving the interval 30 times leaves the stop within a step / 2³⁰ of the
    crossing, where the gap is still positive and Coal's witness points are defined.
    """
    for _ in range(30):
        middle = 0.5 * (apart + touching)
        if pin_.gap(slide.yielded(pose_at(middle)), target, exact=True) > clearance:
            apart = middle
        else:
            touching = middle
    pose = pose_at(touching)
    deflection = slide.deflection(pose)
    point = pin_.distance(slide.yielded(pose, deflection), target, exact=True)[2]
    return ScrapeEnd(touching, "touch", deflection, target.obstacle, point)
