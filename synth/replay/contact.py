"""What a held pin touches along a motion: conservative advancement with Coal, and hole guidance.

**Free flight** (:func:`first_contact`). The pin's true pose along one motion segment is a
function P(s), s ∈ [0, 1], with a bound ``speed`` ≥ |dx/ds| on the speed of every point x of
the pin. A pin at distance d from every obstacle cannot touch one before s + d/speed, so the
search steps s ← s + (d − c/2)/speed (conservative advancement, as
:mod:`synth.models.arm.sweep` does for the arm) until the distance is at most the contact
clearance c: it can never step over a thin obstacle, and a stop leaves the pin between c/2 and
c from the surface it reached. Distances come from Coal (GJK/EPA on the pin's convex solid and
each obstacle: exact on the meshes near contact, bounding spheres and convex hulls far away).
Every step also watches each hole's mouth plane: a tip that crosses it with its tip circle
inside the mouth has been captured (:mod:`synth.replay.capture`); a contact whose tip circle is
inside a mouth of the obstacle it touches is a capture too (the chamfer). Given the friction μ,
a capture at a tilt past the two-point wedging onset is a wedge instead
(:mod:`synth.replay.wedging`). Any other contact stops the pin on the surface.

**Guided** (:func:`guided_motion`). A pin in a hole's bore follows the hole's axis: the hole
takes the pin's lateral error and its tilt, the arm complies. Along the commanded path its tip
depth is the commanded tip's depth along the axis. The guided phase ends when the pin bottoms
at its seated depth (force rises), when its tip leaves the mouth (``exit_margin`` above it), or
when the commanded path drags it more than ``compliance`` sideways (the pin jams).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Literal

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.models.arm.collision import Obstacle, convex_hull
from synth.models.workcell import HoleSite, PinModel
from synth.replay.capture import TipPlacement, captures, seat_depth, tip_placement
from synth.replay.wedging import wedges

__all__ = ["GuidedEnd", "PinContact", "ScrapeEnd", "first_contact", "guided_motion", "scrape"]

PoseAt = Callable[[float], pin.SE3]
"""s ∈ [0, 1] ↦ the pin's true world pose [m]."""

_NEAR = 3e-3
"""[m] below this convex-hull distance the exact mesh distance is computed."""
_FAR = 0.05
"""[m] beyond this bounding-sphere distance the sphere bound is used."""
_MAX_STEPS = 20_000
_BISECTIONS = 40


@dataclass(frozen=True, eq=False)
class PinContact:
    """The first contact of the pin along a segment.

    ``s``: the path parameter; ``kind``: ``capture`` (into ``hole``), ``wedge`` (captured at a
    tilt that wedges it there, :mod:`synth.replay.wedging`) or ``surface``;
    ``obstacle``: the name of what was touched; ``normal``: the obstacle's unit surface normal
    there, pointing at the pin (world); ``point``: the contact point on the obstacle [m];
    ``pin_point``: the pin's nearest point in the pin frame [m]; ``distance`` [m].
    """

    s: float
    kind: Literal["capture", "surface", "wedge"]
    obstacle: str
    hole: HoleSite | None
    normal: NDArray[np.float64]
    point: NDArray[np.float64]
    pin_point: NDArray[np.float64]
    distance: float


class _Target:
    """One obstacle with its bounding sphere and convex hull, ready for distance queries."""

    def __init__(self, obstacle: Obstacle) -> None:
        self.obstacle = obstacle
        geometry = obstacle.geometry
        geometry.computeLocalAABB()
        self.centre = obstacle.pose.act(np.asarray(geometry.aabb_center, dtype=float))
        self.radius = float(geometry.aabb_radius)
        self.hull = convex_hull(geometry)
        self.exact_hull = self.hull is geometry
        self.transform = coal.Transform3s(obstacle.pose.rotation, obstacle.pose.translation)


class _Mouths:
    """The holes' mouth planes, stacked: the tip's height above each, in one product."""

    def __init__(self, holes: Sequence[HoleSite]) -> None:
        self.origins = np.array([h.world_from_hole.translation for h in holes]).reshape(-1, 3)
        self.axes = np.array([h.axis for h in holes]).reshape(-1, 3)

    def axial(self, pin_pose: pin.SE3) -> NDArray[np.float64]:
        """Height [m] of the tip centre above each mouth plane (negative: below)."""
        offsets = pin_pose.translation[None, :] - self.origins
        return np.einsum("ij,ij->i", offsets, self.axes)

    def placement(self, pin_pose: pin.SE3) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Height [m] of the tip centre above each mouth plane and its distance from the axis."""
        offsets = pin_pose.translation[None, :] - self.origins
        axial = np.einsum("ij,ij->i", offsets, self.axes)
        radial = offsets - axial[:, None] * self.axes
        return axial, np.sqrt(np.einsum("ij,ij->i", radial, radial))


class _Pin:
    def __init__(self, model: PinModel) -> None:
        self.model = model
        model.geometry.computeLocalAABB()
        self.centre = np.asarray(model.geometry.aabb_center, dtype=float)
        self.radius = float(model.geometry.aabb_radius)
        self.request = coal.DistanceRequest()
        self.request.enable_signed_distance = False
        self.result = coal.DistanceResult()

    def distance(
        self, pose: pin.SE3, target: _Target, exact: bool
    ) -> tuple[float, NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Distance [m], Coal's normal (pin → obstacle), nearest points on obstacle and pin."""
        geometry = target.obstacle.geometry if exact else target.hull
        self.result.clear()
        tf = coal.Transform3s(pose.rotation, pose.translation)
        d = coal.distance(
            self.model.geometry, tf, geometry, target.transform, self.request, self.result
        )
        normal = np.asarray(self.result.normal, dtype=float)
        point = np.asarray(self.result.getNearestPoint2(), dtype=float)
        on_pin = np.asarray(self.result.getNearestPoint1(), dtype=float)
        return float(d), normal, point, on_pin

    def gap(self, pose: pin.SE3, target: _Target, exact: bool) -> float:
        """The distance [m] of :meth:`distance` alone (no witness points copied out)."""
        geometry = target.obstacle.geometry if exact else target.hull
        self.result.clear()
        tf = coal.Transform3s(pose.rotation, pose.translation)
        return float(
            coal.distance(
                self.model.geometry, tf, geometry, target.transform, self.request, self.result
            )
        )


def _bound(pin_: _Pin, pose: pin.SE3, target: _Target) -> tuple[float, bool]:
    """A lower bound on the distance and whether it is exact enough to stop on."""
    centre = pose.act(pin_.centre)
    sphere = float(np.linalg.norm(centre - target.centre)) - pin_.radius - target.radius
    if sphere > _FAR:
        return sphere, False
    d = pin_.distance(pose, target, exact=False)[0]
    if d > _NEAR or target.exact_hull:
        return d, target.exact_hull
    return pin_.distance(pose, target, exact=True)[0], True


_SLACK = 1e-6
"""[m] margin on the lower bounds of :func:`first_contact`'s lazy queries, above the rounding
of GJK's distances; a target whose bound comes within it of deciding a step is measured."""


class _Track:
    """One target's distances measured along one path: the lower bounds of the fast path.

    The pin's points move at most ``speed`` per unit s, so a distance d measured at s₀ is at
    least d − speed·|s − s₀| at s, for the hull and for the mesh alike.
    """

    def __init__(self, target: _Target) -> None:
        self.target = target
        self.hull, self.s_hull = -np.inf, 0.0
        self.mesh, self.s_mesh = -np.inf, 0.0

    def lower(self, s: float, speed: float) -> float:
        """A lower bound [m] on what :func:`_bound` returns at ``s`` once the sphere test fails.

        :func:`_bound` returns the hull distance h when h > ``_NEAR`` (or the hull is the
        solid), else the mesh distance m ≥ h; so it is at least max(H, min(_NEAR, M)) with H
        and M the hull's and mesh's Lipschitz bounds.
        """
        lb_hull = self.hull - speed * abs(s - self.s_hull)
        if self.target.exact_hull:
            return lb_hull - _SLACK
        lb_mesh = self.mesh - speed * abs(s - self.s_mesh)
        return max(lb_hull, min(_NEAR, lb_mesh)) - _SLACK

    def measure(self, pin_: _Pin, pose: pin.SE3, s: float) -> tuple[float, bool]:
        """:func:`_bound`'s value and exactness at ``s`` past the sphere test, recorded."""
        target = self.target
        d = pin_.gap(pose, target, exact=False)
        self.hull, self.s_hull = d, s
        if d > _NEAR or target.exact_hull:
            return d, target.exact_hull
        d = pin_.gap(pose, target, exact=True)
        self.mesh, self.s_mesh = d, s
        return d, True


def _first_contact_fast(
    pin_model: PinModel,
    pose_at: PoseAt,
    speed: float,
    obstacles: Sequence[Obstacle],
    holes: Sequence[HoleSite],
    start: float,
    end: float,
    clearance: float,
    friction: float | None,
) -> PinContact | None:
    """:func:`first_contact` measuring only the targets that can decide a step.

    Every step of the reference loop takes, per target, the bound d_k of :func:`_bound`; it
    stops at the first target (in order) whose exact d_k is within its limit, else steps by
    min_k (d_k − ½·limit_k)/speed. Here the sphere bounds are computed for every target
    (one product), and a target past the sphere test is measured only when its lower bound
    (:class:`_Track`) reaches its limit or the smallest value found so far; the others are
    strictly above both, so the stop, the step and the contact are the reference's.

    A hole's mouth crossing is located (bisection) only if its tip circle can be inside the
    mouth there: the tip centre's distance from the axis is 1-Lipschitz in its position, so
    over [s, s'] it is at least (ℓ(s) + ℓ(s') − speed·(s' − s))/2; above the mouth radius no
    capture is possible (:func:`captures` needs ℓ ≤ r_m), and the reference would only find
    that out after bisecting.
    """
    pin_ = _Pin(pin_model)
    targets = [_Target(o) for o in obstacles]
    tracks = [_Track(t) for t in targets]
    centres = np.array([t.centre for t in targets]).reshape(-1, 3)
    radii = np.array([t.radius for t in targets])
    mouth_radii = np.array([h.mouth_radius for h in holes])
    s = start
    pose = pose_at(s)
    limits = [clearance] * len(targets)
    for k, target in enumerate(targets):
        d0, exact = _bound(pin_, pose, target)
        if exact and d0 <= clearance:
            limits[k] = 0.5 * d0
    mouths = _Mouths(holes)
    axial, lateral = mouths.placement(pose)
    for _ in range(_MAX_STEPS):
        gaps = np.linalg.norm(pose.act(pin_.centre)[None, :] - centres, axis=1)
        spheres = gaps - pin_.radius - radii
        values: list[float | None] = [None] * len(targets)
        for k, track in enumerate(tracks):
            if spheres[k] > _FAR:
                values[k] = float(spheres[k])
            elif track.lower(s, speed) <= limits[k]:
                d, exact = track.measure(pin_, pose, s)
                if exact and d <= limits[k]:
                    return _classify(pin_, pose, s, targets[k], holes, friction)
                values[k] = d
        step_d = min(
            (v - 0.5 * lim for v, lim in zip(values, limits, strict=True) if v is not None),
            default=np.inf,
        )
        for k, track in enumerate(tracks):
            if values[k] is None and track.lower(s, speed) - 0.5 * limits[k] <= step_d:
                d, _ = track.measure(pin_, pose, s)
                values[k] = d
                step_d = min(step_d, d - 0.5 * limits[k])
        if s >= end:
            return None
        if speed <= 0.0:
            return None
        s_next = min(end, s + max(step_d, 0.0) / speed)
        if s_next <= s:  # numerically stuck at a touching obstacle
            s_next = min(end, s + 1e-9)
        pose_next = pose_at(s_next)
        axial_next, lateral_next = mouths.placement(pose_next)
        crossed = np.flatnonzero((axial > 0.0) & (axial_next <= 0.0))
        reach = 0.5 * (lateral + lateral_next - speed * (s_next - s)) - _SLACK
        for index in crossed.tolist():
            if reach[index] > mouth_radii[index]:
                continue  # no point of [s, s_next] has the tip circle inside the mouth
            hole = holes[index]
            crossing = _crossing(hole, pose_at, s, s_next)
            placement = tip_placement(hole, pose_at(crossing))
            if captures(hole, pin_model, placement):
                axis = hole.axis
                point = hole.world_from_hole.translation.copy()
                kind = _entry(hole, pin_model, placement, friction)
                return PinContact(crossing, kind, hole.owner, hole, axis, point, np.zeros(3), 0.0)
        axial, lateral = axial_next, lateral_next
        s, pose = s_next, pose_next
    raise RuntimeError("pin contact search did not converge")


def first_contact(
    pin_model: PinModel,
    pose_at: PoseAt,
    speed: float,
    obstacles: Sequence[Obstacle],
    holes: Sequence[HoleSite],
    *,
    start: float = 0.0,
    end: float = 1.0,
    clearance: float = 2e-5,
    friction: float | None = None,
    reference: bool = False,
) -> PinContact | None:
    """The first contact of the pin over s ∈ [start, end], or None (see the module docstring).

    ``reference`` measures every target at every step; the default measures only those that
    can decide a step (:func:`_first_contact_fast`) and finds the same contact.

    With ``friction`` (μ) a capture at a tilt that wedges the pin is a ``wedge`` contact.

    ``speed`` [m per unit s] bounds the speed of every point of the pin along the path;
    ``clearance`` [m] is the distance that counts as touching. A pin that starts closer than
    ``clearance`` to an obstacle (it rests where a previous motion stopped it) counts as
    touching that obstacle only below half its starting distance.
    """
    if not reference:
        return _first_contact_fast(
            pin_model, pose_at, speed, obstacles, holes, start, end, clearance, friction
        )
    pin_ = _Pin(pin_model)
    targets = [_Target(o) for o in obstacles]
    s = start
    pose = pose_at(s)
    limits = [clearance] * len(targets)
    for k, target in enumerate(targets):
        d0, exact = _bound(pin_, pose, target)
        if exact and d0 <= clearance:
            limits[k] = 0.5 * d0
    mouths = _Mouths(holes)
    axial = mouths.axial(pose)
    for _ in range(_MAX_STEPS):
        distances = []
        for k, target in enumerate(targets):
            d, exact = _bound(pin_, pose, target)
            if exact and d <= limits[k]:
                return _classify(pin_, pose, s, target, holes, friction)
            distances.append(d - 0.5 * limits[k])
        step_d = min(distances, default=np.inf)
        if s >= end:
            return None
        if speed <= 0.0:
            return None
        s_next = min(end, s + max(step_d, 0.0) / speed)
        if s_next <= s:  # numerically stuck at a touching obstacle
            s_next = min(end, s + 1e-9)
        pose_next = pose_at(s_next)
        axial_next = mouths.axial(pose_next)
        crossed = np.flatnonzero((axial > 0.0) & (axial_next <= 0.0))
        axial = axial_next
        for index in crossed.tolist():
            hole = holes[index]
            crossing = _crossing(hole, pose_at, s, s_next)
            placement = tip_placement(hole, pose_at(crossing))
            if captures(hole, pin_model, placement):
                axis = hole.axis
                point = hole.world_from_hole.translation.copy()
                kind = _entry(hole, pin_model, placement, friction)
                return PinContact(crossing, kind, hole.owner, hole, axis, point, np.zeros(3), 0.0)
        s, pose = s_next, pose_next
    raise RuntimeError("pin contact search did not converge")


def _crossing(hole: HoleSite, pose_at: PoseAt, lo: float, hi: float) -> float:
    """The s in [lo, hi] where the tip crosses the mouth plane (bisection on the axial height)."""
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        if tip_placement(hole, pose_at(mid)).axial > 0.0:
            lo = mid
        else:
            hi = mid
    return hi


def _entry(
    hole: HoleSite, model: PinModel, placement: TipPlacement, friction: float | None
) -> Literal["capture", "wedge"]:
    """``wedge`` if a pin captured at ``placement`` wedges (:func:`wedges`), else ``capture``."""
    if friction is None:
        return "capture"
    bore, shaft = 2.0 * hole.radius, 2.0 * model.radius
    stuck = wedges(placement.tilt, bore, shaft, friction, seat_depth(hole, model))
    return "wedge" if stuck else "capture"


def _classify(
    pin_: _Pin,
    pose: pin.SE3,
    s: float,
    target: _Target,
    holes: Sequence[HoleSite],
    friction: float | None = None,
) -> PinContact:
    d, normal, point, on_pin = pin_.distance(pose, target, exact=True)
    local = pose.actInv(on_pin)
    name = target.obstacle.name
    for hole in holes:
        if hole.owner != name:
            continue
        placement = tip_placement(hole, pose)
        if placement.axial <= hole.mouth_radius and captures(hole, pin_.model, placement):
            kind = _entry(hole, pin_.model, placement, friction)
            return PinContact(s, kind, name, hole, hole.axis, point, local, d)
    # Coal's normal points from the pin to the obstacle; the surface normal is opposite
    norm = float(np.linalg.norm(normal)) if np.all(np.isfinite(normal)) else 0.0
    outward = -normal / norm if norm > 1e-12 else np.zeros(3)
    if not (np.all(np.isfinite(point)) and np.all(np.isfinite(local))):
        point, local = pose.translation.copy(), np.zeros(3)  # degenerate: use the tip
    return PinContact(s, "surface", name, None, outward, point, local, d)


@dataclass(frozen=True)
class GuidedEnd:
    """How a guided phase ends: at ``s``, by ``kind``, with the tip ``depth`` [m] there."""

    s: float
    kind: Literal["bottom", "exit", "jam", "end"]
    depth: float
    lateral: float


def guided_motion(
    hole: HoleSite,
    pose_at: PoseAt,
    *,
    seat: float,
    start: float = 0.0,
    end: float = 1.0,
    compliance: float = 0.01,
    exit_margin: float = 1e-3,
    samples: int = 64,
) -> GuidedEnd:
    """The end of a pin's guided phase in ``hole`` over s ∈ [start, end] (module docstring).

    ``pose_at`` is the *commanded* pin pose (where the arm would carry it without the hole);
    ``seat`` [m] is the depth at which the pin bottoms. The commanded path is sampled at
    ``samples`` points and the first event is located by bisection.
    """

    def state(s: float) -> tuple[float, float]:
        p = tip_placement(hole, pose_at(s))
        return -p.axial, p.lateral

    # a pin already at (or past) its seat bottoms only if the path pushes it further in
    depth0, _ = state(start)
    bottom = seat if depth0 < seat else depth0 + 1e-9

    def event(s: float) -> Literal["bottom", "exit", "jam"] | None:
        depth, lateral = state(s)
        if depth >= bottom:
            return "bottom"
        if lateral > compliance:
            return "jam"
        if depth <= -exit_margin:
            return "exit"
        return None

    previous = start
    for s in np.linspace(start, end, max(samples, 2))[1:]:
        if event(float(s)) is None:
            previous = float(s)
            continue
        lo, hi = previous, float(s)
        for _ in range(_BISECTIONS):
            mid = 0.5 * (lo + hi)
            if event(mid) is None:
                lo = mid
            else:
                hi = mid
        kind = event(hi)
        assert kind is not None
        depth, lateral = state(hi)
        return GuidedEnd(hi, kind, min(max(depth, 0.0), seat), lateral)
    depth, lateral = state(end)
    return GuidedEnd(end, "end", min(max(depth, 0.0), seat), lateral)


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
    pin_ = _Pin(pin_model)
    target = _Target(obstacle)
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
