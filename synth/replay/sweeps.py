"""The arm's sweep along one segment of a motion: collisions, the hand's contacts and slides.

The arm links, the palm and the fingers (at their true opening) are swept along the straight
joint-space segment (:func:`synth.models.arm.swept_segment`, conservative advancement on Coal
distances) against the table, the objects, the free pins and each other. The first pair that
comes within the sweep's clearance decides:

* an arm link: a ``collision`` violation at that instant;
* the palm or a finger against the workcell: the wrist's force sensor feels it, a contact
  (:class:`~synth.replay.motion.Stop` of kind ``surface``), backed off to where the pair is at
  least a quarter of the clearance apart. A push that meets the surface at less than
  ``slide_angle`` slides along it instead: the pair is left out while the arm yields along the
  surface normal, until the path clears the surface (the sweep goes on from there) or the arm
  would have to yield more than the compliance (a contact: jammed).

A motion that starts closer than the clearance (a finger resting where a previous motion
stopped it) is a collision only if it comes closer still (:func:`sweep_options`).
"""

from __future__ import annotations

import math
from collections.abc import Collection
from dataclasses import dataclass, replace

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.models.arm import (
    HAND_BODIES,
    Arm,
    CollisionScene,
    SweepOptions,
    SweepResult,
    swept_segment,
)
from synth.models.arm.sweep import LAZY_SLACK
from synth.replay.advance import fast_sweep
from synth.replay.bounds import ArmChain
from synth.replay.cell import ReplayOptions
from synth.replay.motion import Segment, Stop, push_reaction
from synth.replay.reach import describe_pose
from synth.replay.report import Violation
from synth.replay.tubes import Tubes
from synth.vec3 import norm3

__all__ = [
    "SweepContext",
    "pair_collisions",
    "pair_contact",
    "pair_distances",
    "sweep_options",
    "sweep_segment",
]


@dataclass(frozen=True)
class SweepContext:
    """What the sweeps of one motion need: the arm, the settings and the motion's facts.

    ``obstacles``: the names of the workcell's solids and free pins (what a hand body can
    touch); ``line``: the motion's AL line; ``start_time`` [s]: the clock when it started;
    ``chain``: the arm's chain for the fast path's motion bounds.
    """

    arm: Arm
    options: ReplayOptions
    obstacles: Collection[str]
    line: int
    start_time: float
    chain: ArmChain


def sweep_options(
    options: ReplayOptions, scene: CollisionScene, q: NDArray[np.float64]
) -> SweepOptions:
    """The sweep's options, with the clearance halved below a contact the motion starts in.

    A motion that starts where a previous one stopped on contact (a finger on the box top)
    begins closer than the clearance; it is a collision only if it comes closer still.
    """
    sweep = options.sweep
    if not scene.pairs:
        return sweep
    if options.reference:
        start = float(np.min(scene.distance_bounds(q, exact_below=sweep.clearance)))
    else:
        # only pairs whose lower bound reaches the clearance can be below it
        sweep = replace(sweep, lazy=True)
        below = np.full(len(scene.pairs), sweep.clearance)
        lower = scene.lower_bounds(q, below) - LAZY_SLACK
        close = np.flatnonzero(lower <= below).tolist()
        near = [scene.measure(k, sweep.clearance) for k in close]
        start = min(near, default=np.inf)
    if start >= sweep.clearance:
        return sweep
    return SweepOptions(
        clearance=max(0.5 * start, 0.0), max_checks=sweep.max_checks, lazy=sweep.lazy
    )


def sweep_segment(
    context: SweepContext, scene: CollisionScene, seg: Segment, limit: float
) -> Stop | None:
    """Sweep the arm and hand over s ∈ [0, limit] of ``seg``: the first stop, if any.

    A palm or finger pushed along a surface at a grazing angle slides: its pair is left out
    until the path clears the surface (the rest is still swept), then the sweep goes on.
    """
    start = 0.0
    while start < limit:
        sweep = _swept(context, scene, seg.q(start), seg.q(limit))
        if sweep.free:
            return None
        s_hit = start + sweep.s * (limit - start)
        found = _sweep_stop(context, scene, seg, start, s_hit, limit, sweep)
        if isinstance(found, Stop):
            return found
        s_free, pair = found
        relaxed = CollisionScene(
            context.arm,
            scene.environment,
            held=scene.held,
            allowed=[*scene.allowed, pair],
            opening=scene.opening,
        )
        inner = _swept(context, relaxed, seg.q(s_hit), seg.q(s_free))
        if not inner.free:
            s_in = s_hit + inner.s * (s_free - s_hit)
            found = _sweep_stop(context, relaxed, seg, s_hit, s_in, s_free, inner, slide=False)
            assert isinstance(found, Stop)
            return found
        start = s_free
    return None


def _swept(
    context: SweepContext, scene: CollisionScene, q0: NDArray[np.float64], q1: NDArray[np.float64]
) -> SweepResult:
    """The swept check of q0 → q1, its clearance halved below a contact it starts in.

    The reference path's (:func:`sweep_options`, :func:`~synth.models.arm.swept_segment`) or
    the fast path's: :func:`~synth.replay.advance.fast_sweep` on the pairs that no tube of an
    earlier sweep keeps clear (:mod:`synth.replay.tubes`); a free sweep that no tube helped
    leaves one for the next trials.
    """
    if context.options.reference:
        return swept_segment(scene, q0, q1, sweep_options(context.options, scene, q0))
    options = context.options.sweep
    tubes = Tubes.of(scene)
    left = tubes.unproven(scene, context.chain, q0, q1, options.clearance)
    sweep = fast_sweep(scene, context.chain, q0, q1, options, only=left)
    if sweep.free and left is None:
        tubes.build(context.line, scene, context.chain, q0, q1, options)
    return sweep


def _sweep_stop(
    context: SweepContext,
    scene: CollisionScene,
    seg: Segment,
    start: float,
    s_hit: float,
    limit: float,
    sweep: SweepResult,
    *,
    slide: bool = True,
) -> Stop | tuple[float, tuple[str, str]]:
    """What the sweep's first close pair means.

    A violation (an arm link), a sensed contact of the palm or a finger, or their slide,
    returned as (where the path clears the surface, the pair).
    """
    a, b = sweep.pair if sweep.pair is not None else ("?", "?")
    obstacles = context.obstacles
    if b in HAND_BODIES and a in obstacles:
        a, b = b, a
    if a not in HAND_BODIES or b not in obstacles:
        detail = (
            f"{a} hit {b} ({100 * sweep.distance:.2f} cm apart) at "
            f"{describe_pose(context.arm.forward(sweep.q))}"
        )
        time = context.start_time + seg.time(s_hit)
        violation = Violation("collision", context.line, detail, time)
        return Stop(s_hit, "violation", a, b, violation=violation)
    # the palm or a finger touches the workcell: the wrist sensor feels it
    k = scene.pairs.index((a, b)) if (a, b) in scene.pairs else scene.pairs.index((b, a))
    point, on_body, normal = pair_contact(scene, seg.q(s_hit), a, b)
    local = scene.body_pose(seg.q(s_hit), a).actInv(on_body)

    def body_point(x: float) -> NDArray[np.float64]:
        return np.asarray(scene.body_pose(seg.q(x), a).act(local), dtype=float)

    reaction = push_reaction(body_point, s_hit)
    options = context.options
    note = ""
    if slide and float(reaction @ normal) < math.sin(options.slide_angle):
        origin = body_point(s_hit)
        moved = float(np.linalg.norm(body_point(min(limit, s_hit + 1e-3)) - origin))
        ds = 1e-3 * 2e-4 / moved if moved > 0.0 else limit - s_hit
        s = s_hit
        while s < limit:
            s = min(limit, s + ds)
            deflection = -float(normal @ (body_point(s) - origin))
            if deflection > options.compliance:
                note = f"slid along it and jammed, {100 * deflection:.2f} cm in"
                break
            if pair_distance(scene, seg.q(s), k) > options.sweep.clearance:
                return s, (a, b)
        else:
            return limit, (a, b)
    s_stop = _back_off(options, scene, seg, start, s_hit, k)
    return Stop(s_stop, "surface", a, b, point, reaction, note=note)


def pair_distances(scene: CollisionScene, q: NDArray[np.float64], pairs: list[int]) -> list[float]:
    """Exact distances [m] of the scene's ``pairs`` at ``q`` (meshes themselves)."""
    if not pairs:
        return []
    pin.updateGeometryPlacements(
        scene.model, scene.data, scene.geometry_model, scene.geometry_data, q
    )
    out = []
    for k in pairs:
        pin.computeDistance(scene.geometry_model, scene.geometry_data, k)
        out.append(float(scene.geometry_data.distanceResults[k].min_distance))
    return out


def pair_collisions(
    scene: CollisionScene, q: NDArray[np.float64], pairs: list[int]
) -> list[tuple[str, str]]:
    """Those of the scene's ``pairs`` in contact at ``q``, in order."""
    if not pairs:
        return []
    pin.updateGeometryPlacements(
        scene.model, scene.data, scene.geometry_model, scene.geometry_data, q
    )
    return [
        scene.pairs[k]
        for k in pairs
        if pin.computeCollision(scene.geometry_model, scene.geometry_data, k)
    ]


def pair_distance(scene: CollisionScene, q: NDArray[np.float64], k: int) -> float:
    """Exact distance [m] of the scene's pair ``k`` at ``q``."""
    pin.updateGeometryPlacements(
        scene.model, scene.data, scene.geometry_model, scene.geometry_data, q
    )
    pin.computeDistance(scene.geometry_model, scene.geometry_data, k)
    return float(scene.geometry_data.distanceResults[k].min_distance)


def _back_off(
    options: ReplayOptions,
    scene: CollisionScene,
    seg: Segment,
    start: float,
    s_hit: float,
    k: int,
) -> float:
    """A stop in [start, s_hit] where pair ``k`` is at least a quarter clearance apart."""
    quarter = 0.25 * options.sweep.clearance
    if pair_distance(scene, seg.q(s_hit), k) >= quarter:
        return s_hit
    lo, hi = start, s_hit
    for _ in range(16):
        mid = 0.5 * (lo + hi)
        if pair_distance(scene, seg.q(mid), k) >= 2 * quarter:
            lo = mid
        else:
            hi = mid
    return lo


def pair_contact(
    scene: CollisionScene, q: NDArray[np.float64], a: str, b: str
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Nearest points on ``b`` and on ``a`` at ``q`` [m], and b's surface normal towards a."""
    geometry = {body.name: body.geometry for body in scene.bodies}
    pa, pb = scene.body_pose(q, a), scene.body_pose(q, b)
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    coal.distance(
        geometry[a],
        coal.Transform3s(pa.rotation, pa.translation),
        geometry[b],
        coal.Transform3s(pb.rotation, pb.translation),
        request,
        result,
    )
    normal = -np.asarray(result.normal, dtype=float)  # Coal's points from a to b
    norm = norm3(normal) if np.all(np.isfinite(normal)) else 0.0
    normal = normal / norm if norm > 1e-12 else np.zeros(3)
    on_b = np.asarray(result.getNearestPoint2(), dtype=float)
    on_a = np.asarray(result.getNearestPoint1(), dtype=float)
    return on_b, on_a, normal
