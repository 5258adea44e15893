"""What a held pin first touches along a motion: conservative advancement with Coal.

**Free flight** (:func:`first_contact`). The pin's true pose along one motion segment is a
function P(s), s ∈ [0, 1]. A pin at distance d from every obstacle, whose points move at most
D(h) between s and s + h, cannot touch one before D(h) reaches d, so the search steps s ← s + h
with D(h) = d − c/2 (conservative advancement, as :mod:`synth.models.arm.sweep` does for the
arm) until the distance is at most the contact clearance c: it can never step over a thin
obstacle, and a stop leaves the pin between c/2 and c from the surface it reached. Distances
come from Coal (GJK/EPA on the pin's convex solid and each obstacle: exact on the meshes near
contact). Every step also watches each hole's mouth plane: a tip that crosses it with its tip
circle inside the mouth has been captured (:mod:`synth.replay.capture`); a contact whose tip
circle is inside a mouth of the obstacle it touches is a capture too (the chamfer). Given the
friction μ, a capture at a tilt past the two-point wedging onset is a wedge instead
(:mod:`synth.replay.wedging`). Any other contact stops the pin on the surface.

*The reference path* (``reference=True``) bounds D(h) = speed·h with one constant for the whole
segment and measures every obstacle at every step: by its bounding sphere far away, by its
convex hull nearer, on its mesh within 3 mm.

*The fast path* (a :class:`~synth.replay.bounds.PinFlight`) bounds D(h) = h·V(s) + ½·A·h² with
the pin's speed V(s) exact at s (its joint's velocity there) and A a proven bound on the second
derivative (:mod:`synth.replay.bounds`), so it steps close to the true time to contact, and it
asks Coal only what can decide a step. Two cheap lower bounds on an obstacle's distance come
first: its bounding sphere's, and for a box or a mesh's convex hull (an intersection of
half-spaces n_i·x ≤ b_i) the separation g_i = min over the pin's vertices y of n_i·y − b_i
(every pin point beyond the plane by g_i, every obstacle point behind it: the two are ≥ g_i
apart). A plane's separation shrinks no faster than the pin's points approach it along −n_i,
so it gives its own step, often far longer than the distance's (a pin lifted off a surface
moves away from its plane and is not held back by it at all). An obstacle whose cheap bound
reaches its contact limit is measured with Coal (the contact test is always Coal's, on the
mesh); one whose cheap step would be the shortest is measured before it is allowed to decide
the step. A crossing of a mouth plane is found at the step points as on the reference path; a
step that could dip the tip below a mouth and back (inside the mouth's reach) is shortened
until the tip's height is either provably positive or provably falling over the whole step.

The guided phase that follows a capture is :mod:`synth.replay.guided`'s; a slide along a
surface, :mod:`synth.replay.scrape`'s.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.models.arm.collision import Obstacle, convex_hull
from synth.models.spec import DEFAULT_FRICTION
from synth.models.workcell import HoleSite, PinModel
from synth.replay.bounds import PinFlight, safe_step
from synth.replay.capture import TipPlacement, captures, seat_depth, tip_placement
from synth.replay.guided import BISECTIONS, event_crossing
from synth.replay.motion import PoseAt
from synth.replay.wedging import wedges
from synth.vec3 import cross3, norm3

__all__ = ["GJK_MARGIN", "PinContact", "PinGeometry", "Target", "first_contact", "pin_points"]

_NEAR = 3e-3
"""[m] below this convex-hull distance the exact mesh distance is computed."""
_FAR = 0.05
"""[m] beyond this bounding-sphere distance the sphere bound is used."""
_MAX_STEPS = 20_000


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


@dataclass(frozen=True, eq=False)
class _Solid:
    """What a solid's distance bounds need, in its own frame, computed once per solid.

    ``centre``, ``radius``: the ball around its bounding box [m]; ``hull``: its convex hull
    (the solid itself unless it is a mesh); ``normals`` (rows) and ``offsets`` [m]: the hull's
    half-spaces n·x ≤ b when it is a box or a mesh's hull of few faces (None otherwise);
    ``corners`` (columns) [m]: the hull's vertices, whose convex hull it is (a box's eight, a
    convex solid's points; None for a round primitive).
    """

    centre: NDArray[np.float64]
    radius: float
    hull: coal.CollisionGeometry
    normals: NDArray[np.float64] | None
    offsets: NDArray[np.float64] | None
    corners: NDArray[np.float64] | None


_MAX_PLANES = 32
"""Hulls with more distinct faces than this get no plane bound (a free pin's round hull)."""

_SOLIDS: dict[int, tuple[coal.CollisionGeometry, _Solid]] = {}

GJK_MARGIN = 2e-3
"""Relative: Coal's distance d may exceed the true distance (its GJK stops within tolerance);
the separation along its own witness direction, computed exactly, was found up to 1·10⁻³·d
below it on the seed's solids. Steps take d·(1 − 2·10⁻³) as the distance's lower bound."""


def _below(d: NDArray[np.float64] | float) -> NDArray[np.float64] | float:
    """A lower bound on the true distance from Coal's ``d`` [m] (:data:`GJK_MARGIN`)."""
    return d * (1.0 - GJK_MARGIN)


def _half_spaces(
    geometry: coal.CollisionGeometry, hull: coal.CollisionGeometry
) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """The half-spaces n·x ≤ b (local frame) whose intersection is the hull, if few."""
    if isinstance(geometry, coal.Box):
        half = np.asarray(geometry.halfSide, dtype=float)
        normals = np.vstack([np.eye(3), -np.eye(3)])
        return normals, np.concatenate([half, half])
    if not isinstance(hull, coal.ConvexBase) or hull.num_normals_and_offsets == 0:
        return None
    normals = np.asarray(hull.normals(), dtype=float).reshape(-1, 3)
    offsets = -np.asarray(hull.offsets(), dtype=float).reshape(-1)  # Coal: n·x + offset ≤ 0
    points = np.asarray(hull.points(), dtype=float).reshape(-1, 3)
    if np.max(points @ normals.T - offsets[None, :]) > 1e-9:
        return None  # not the convention assumed: no plane bound rather than a wrong one
    planes = np.unique(np.round(np.column_stack([normals, offsets]), 12), axis=0)
    if planes.shape[0] > _MAX_PLANES:
        return None
    # the rounded planes must still hold every hull point
    offsets = planes[:, 3] + 1e-12
    if np.max(points @ planes[:, :3].T - offsets[None, :]) > 0.0:
        return None
    return planes[:, :3], offsets


def _solid(geometry: coal.CollisionGeometry) -> _Solid:
    cached = _SOLIDS.get(id(geometry))
    if cached is not None and cached[0] is geometry:
        return cached[1]
    geometry.computeLocalAABB()
    hull = convex_hull(geometry)
    planes = _half_spaces(geometry, hull)
    corners = None
    if isinstance(geometry, coal.Box):
        half = np.asarray(geometry.halfSide, dtype=float)
        corners = np.array(np.meshgrid(*[[-h, h] for h in half])).reshape(3, -1)
    elif isinstance(hull, coal.ConvexBase):
        corners = np.asarray(hull.points(), dtype=float).reshape(-1, 3).T.copy()
    solid = _Solid(
        np.asarray(geometry.aabb_center, dtype=float).copy(),
        float(geometry.aabb_radius),
        hull,
        None if planes is None else planes[0],
        None if planes is None else planes[1],
        corners,
    )
    _SOLIDS[id(geometry)] = (geometry, solid)
    return solid


class Target:
    """One obstacle with its bounding sphere and convex hull, ready for distance queries."""

    def __init__(self, obstacle: Obstacle) -> None:
        self.obstacle = obstacle
        solid = _solid(obstacle.geometry)
        pose = obstacle.pose
        self.centre = pose.act(solid.centre)
        self.radius = solid.radius
        self.hull = solid.hull
        self.exact_hull = self.hull is obstacle.geometry
        self.transform = coal.Transform3s(pose.rotation, pose.translation)
        self.normals: NDArray[np.float64] | None = None
        self.offsets: NDArray[np.float64] | None = None
        self.corners: NDArray[np.float64] | None = None
        if solid.corners is not None:
            self.corners = pose.rotation @ solid.corners + pose.translation[:, None]
        if solid.normals is not None and solid.offsets is not None:
            self.normals = solid.normals @ pose.rotation.T  # world normals, one per row
            self.offsets = solid.offsets + self.normals @ pose.translation


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


class PinGeometry:
    """The pin's convex solid with its bounding ball, ready for Coal distance queries."""

    def __init__(self, model: PinModel) -> None:
        self.model = model
        model.geometry.computeLocalAABB()
        self.centre = np.asarray(model.geometry.aabb_center, dtype=float)
        self.radius = float(model.geometry.aabb_radius)
        self.request = coal.DistanceRequest()
        self.request.enable_signed_distance = False
        self.result = coal.DistanceResult()

    def distance(
        self, pose: pin.SE3, target: Target, exact: bool
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

    def separation(
        self, pose: pin.SE3, target: Target, exact: bool
    ) -> tuple[float, NDArray[np.float64]]:
        """Distance [m] and Coal's normal (pin → obstacle), no witness points copied out."""
        geometry = target.obstacle.geometry if exact else target.hull
        self.result.clear()
        tf = coal.Transform3s(pose.rotation, pose.translation)
        d = coal.distance(
            self.model.geometry, tf, geometry, target.transform, self.request, self.result
        )
        return float(d), np.asarray(self.result.normal, dtype=float)

    def gap(self, pose: pin.SE3, target: Target, exact: bool) -> float:
        """The distance [m] of :meth:`distance` alone (no witness points copied out)."""
        geometry = target.obstacle.geometry if exact else target.hull
        self.result.clear()
        tf = coal.Transform3s(pose.rotation, pose.translation)
        return float(
            coal.distance(
                self.model.geometry, tf, geometry, target.transform, self.request, self.result
            )
        )


def _bound(pin_: PinGeometry, pose: pin.SE3, target: Target) -> tuple[float, bool]:
    """A lower bound on the distance and whether it is exact enough to stop on."""
    centre = pose.act(pin_.centre)
    sphere = norm3(centre - target.centre) - pin_.radius - target.radius
    if sphere > _FAR:
        return sphere, False
    d = pin_.distance(pose, target, exact=False)[0]
    if d > _NEAR or target.exact_hull:
        return d, target.exact_hull
    return pin_.distance(pose, target, exact=True)[0], True


def pin_points(model: PinModel) -> NDArray[np.float64]:
    """The vertices of the pin's convex solid, pin frame, as columns [m]."""
    geometry = model.geometry
    if isinstance(geometry, coal.ConvexBase):
        return np.asarray(geometry.points(), dtype=float).reshape(-1, 3).T.copy()
    return np.asarray(model.mesh.vertices, dtype=float).T.copy()


class _Field:
    """The targets' cheap lower bounds, stacked: bounding spheres and hull planes.

    ``normals`` (rows, world) and ``offsets`` are every target's half-spaces n·x ≤ b in one
    array, ``owner`` the target of each and ``starts`` where each target's planes begin.
    """

    def __init__(self, pin_: PinGeometry, targets: Sequence[Target], points: NDArray[np.float64]):
        self.pin = pin_
        self.points = points
        self.count = len(targets)
        self.centres = np.array([t.centre for t in targets]).reshape(-1, 3)
        self.radii = np.array([t.radius for t in targets])
        normals, offsets, owner = [], [], []
        for k, target in enumerate(targets):
            if target.normals is not None and target.offsets is not None:
                normals.append(target.normals)
                offsets.append(target.offsets)
                owner.append(np.full(target.offsets.shape[0], k))
        self.normals = np.vstack(normals) if normals else np.zeros((0, 3))
        self.offsets = np.concatenate(offsets) if offsets else np.zeros(0)
        self.owner = np.concatenate(owner) if owner else np.zeros(0, dtype=np.int64)
        self.planed = np.unique(self.owner)
        self.starts = np.searchsorted(self.owner, self.planed)

    def lower(
        self, rotation: NDArray[np.float64], translation: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Per target a lower bound on its distance [m], and every plane's separation [m]."""
        centre = rotation @ self.pin.centre + translation
        offset = centre[None, :] - self.centres
        lower = np.sqrt(np.einsum("ij,ij->i", offset, offset)) - self.pin.radius - self.radii
        if not self.offsets.size:
            return lower, self.offsets
        normals_pin = self.normals @ rotation  # n·(R y + t) = (Rᵀn)·y + n·t
        gaps = np.min(normals_pin @ self.points, axis=1) + self.normals @ translation - self.offsets
        best = np.maximum.reduceat(gaps, self.starts)
        lower[self.planed] = np.maximum(lower[self.planed], best)
        return lower, gaps

    def plane_steps(
        self, gaps: NDArray[np.float64], halves: NDArray[np.float64], flight: PinFlight
    ) -> NDArray[np.float64]:
        """Per target the longest step its planes allow (0 for a target without planes).

        A plane whose separation g exceeds half the target's limit λ keeps the pin beyond
        λ/2 for as long as g − τ·a − ½Aτ² > λ/2, a its approach rate
        (:meth:`~synth.replay.bounds.PinFlight.approach`); the target's step is its best plane's.
        """
        out = np.zeros(self.count)
        if not self.offsets.size:
            return out
        rates = flight.approach(self.normals)
        steps = safe_steps(gaps - halves[self.owner], rates, flight.curvature)
        out[self.planed] = np.maximum.reduceat(steps, self.starts)
        return out


def safe_steps(
    gaps: NDArray[np.float64], rates: NDArray[np.float64] | float, curvature: float
) -> NDArray[np.float64]:
    """:func:`~synth.replay.bounds.safe_step` element by element."""
    gaps = np.asarray(gaps, dtype=float)
    positive = np.maximum(gaps, 0.0)
    root = np.sqrt(np.maximum(np.square(rates) + 2.0 * curvature * positive, 0.0))
    denominator = rates + root
    with np.errstate(divide="ignore", invalid="ignore"):
        steps = np.where(denominator > 0.0, 2.0 * positive / denominator, np.inf)
    return np.where(gaps > 0.0, steps, 0.0)


_PREPARED: dict[tuple[object, ...], tuple[object, ...]] = {}


def _prepared(
    pin_model: PinModel, obstacles: Sequence[Obstacle], holes: Sequence[HoleSite]
) -> tuple[PinGeometry, list[Target], _Field, _Mouths, NDArray[np.float64]]:
    """The pin, targets, bounds and mouths of a search, kept for the next ones.

    A trial's searches look for the same pin among the same solids at the same poses (a free
    pin moves only when it is carried): they are made once per pin, holes and placed solids
    (the last few kept, keyed by the solids' names, shapes and poses).
    """
    key = (
        id(pin_model),
        id(holes),
        tuple((o.name, id(o.geometry), o.pose.homogeneous.tobytes()) for o in obstacles),
    )
    cached = _PREPARED.get(key)
    if cached is not None and cached[0] is pin_model and cached[1] is holes:
        return cached[2]  # type: ignore[return-value]
    pin_ = PinGeometry(pin_model)
    targets = [Target(o) for o in obstacles]
    field = _Field(pin_, targets, pin_points(pin_model))
    mouths = _Mouths(holes)
    radii = np.array([h.mouth_radius for h in holes])
    while len(_PREPARED) >= 4:
        _PREPARED.pop(next(iter(_PREPARED)))
    prepared = (pin_, targets, field, mouths, radii)
    _PREPARED[key] = (pin_model, holes, prepared)
    return prepared


def _first_contact_flight(
    pin_model: PinModel,
    flight: PinFlight,
    obstacles: Sequence[Obstacle],
    holes: Sequence[HoleSite],
    start: float,
    end: float,
    clearance: float,
    friction: float | None,
) -> PinContact | None:
    """:func:`first_contact` on the fast path (see the module docstring for the bounds).

    At each step point: every target whose cheap bound (sphere, planes) reaches its limit is
    measured with Coal and a contact is one whose exact distance is within its limit, the
    first in order, as on the reference path. Then each target gets the longest step its
    bounds allow (isotropic from its sphere or measured distance with the pin's V(s) and A,
    directional from each plane with the pin's approach rate along it), the shortest is
    measured exactly before it may decide, and the step is the shortest over the targets,
    shortened for the mouths (module docstring).
    """
    pin_, targets, field, mouths, mouth_radii = _prepared(pin_model, obstacles, holes)
    count = len(targets)
    curvature = flight.curvature
    limits = np.full(count, clearance)

    s = start
    flight.at(s)
    pose = pin.SE3(flight.rotation, flight.translation)
    lower, gaps = field.lower(flight.rotation, flight.translation)
    exact = np.full(count, np.nan)  # Coal's distance on the solid (the mesh for a mesh)
    aimed = np.zeros(count)  # the step along Coal's separating direction, when measured
    hulled = np.zeros(count, dtype=bool)  # a mesh's hull measured (with its direction)
    for k in np.flatnonzero(lower <= clearance).tolist():
        exact[k] = pin_.gap(pose, targets[k], exact=True)
        if exact[k] <= clearance:
            limits[k] = 0.5 * exact[k]
    halves = 0.5 * limits
    axial, lateral = mouths.placement(pose)

    def witness_step(k: int, d: float, normal: NDArray[np.float64]) -> float:
        """The step along Coal's separating direction n (obstacle → pin) of a convex solid.

        For convex solids the separation along any fixed direction n, min over the pin's
        vertices y of n·y minus max over the obstacle's of n·x, is a lower bound on their
        distance, and along Coal's witness direction it is the distance (within GJK's
        tolerance). It is computed here from the vertices, so it is exact; the obstacle does
        not move, so it shrinks no faster than the pin's points approach along −n.
        """
        norm = norm3(normal)
        if not (d > halves[k] and np.isfinite(norm) and norm > 1e-12):
            return 0.0
        n = -normal / norm
        corners = targets[k].corners
        if corners is None:
            return 0.0
        world = flight.rotation @ field.points + flight.translation[:, None]
        separation = float(np.min(n @ world)) - float(np.max(n @ corners))
        rate = float(flight.approach(n[None, :])[0])
        return safe_step(separation - halves[k], rate, curvature)

    def measure(k: int) -> None:
        """Coal's distance of target k on its solid; for a convex one, its direction too."""
        target = targets[k]
        d, normal = pin_.separation(pose, target, exact=True)
        exact[k] = d
        if target.exact_hull:
            aimed[k] = witness_step(k, d, normal)

    def refine(k: int, speed: float) -> float:
        """Measure target k once more (its solid, then a mesh's hull); its new step."""
        if np.isnan(exact[k]):
            measure(k)
            return max(safe_step(_below(exact[k]) - halves[k], speed, curvature), aimed[k])
        d, normal = pin_.separation(pose, targets[k], exact=False)
        hulled[k] = True
        aimed[k] = max(aimed[k], witness_step(k, d, normal))
        return aimed[k]

    def settled(k: int) -> bool:
        return not np.isnan(exact[k]) and (targets[k].exact_hull or bool(hulled[k]))

    for _ in range(_MAX_STEPS):
        for k in np.flatnonzero(lower <= limits).tolist():
            if np.isnan(exact[k]):
                measure(k)
            if exact[k] <= limits[k]:
                return _classify(pin_, pose, s, targets[k], holes, friction)
        if s >= end:
            return None
        speed = flight.speed
        if speed <= 0.0 and curvature <= 0.0:
            return None  # the pin does not move
        room = end - s
        best = np.where(np.isnan(exact), lower, np.fmax(lower, _below(exact)))
        steps = np.maximum(
            safe_steps(best - halves, speed, curvature), field.plane_steps(gaps, halves, flight)
        )
        steps = np.maximum(steps, aimed)
        while count:
            k = int(np.argmin(steps))
            if steps[k] >= room or settled(k):
                break
            steps[k] = max(steps[k], refine(k, speed))
        h = min(room, float(np.min(steps)) if count else np.inf)
        h = _mouth_guard(flight, pose, mouths, mouth_radii, axial, lateral, h)
        s_next = min(end, s + h)
        if s_next <= s:  # numerically stuck at a touching obstacle
            s_next = min(end, s + 1e-9)
        moved = (s_next - s) * speed + 0.5 * curvature * (s_next - s) ** 2
        flight.at(s_next)
        pose_next = pin.SE3(flight.rotation, flight.translation)
        axial_next, lateral_next = mouths.placement(pose_next)
        crossed = np.flatnonzero((axial > 0.0) & (axial_next <= 0.0))
        if crossed.size:
            moved_back = (s_next - s) * flight.speed + 0.5 * curvature * (s_next - s) ** 2
            nearest = np.maximum(lateral - moved, lateral_next - moved_back)
            for index in crossed.tolist():
                if nearest[index] > mouth_radii[index]:
                    continue  # no point of [s, s_next] has the tip circle inside the mouth
                hole = holes[index]
                crossing = _crossing_flight(hole, flight, s, s_next)
                placement = tip_placement(hole, flight.pose(crossing))
                if captures(hole, pin_model, placement, _mu(friction)):
                    axis = hole.axis
                    point = hole.world_from_hole.translation.copy()
                    kind = _entry(hole, pin_model, placement, friction)
                    return PinContact(
                        crossing, kind, hole.owner, hole, axis, point, np.zeros(3), 0.0
                    )
            flight.at(s_next)  # the bisection moved the flight's state
        s, pose = s_next, pose_next
        axial, lateral = axial_next, lateral_next
        lower, gaps = field.lower(flight.rotation, flight.translation)
        exact[:] = np.nan
        aimed[:] = 0.0
        hulled[:] = False
    raise RuntimeError("pin contact search did not converge")


def _mouth_guard(
    flight: PinFlight,
    pose: pin.SE3,
    mouths: _Mouths,
    mouth_radii: NDArray[np.float64],
    axial: NDArray[np.float64],
    lateral: NDArray[np.float64],
    h: float,
) -> float:
    """``h`` shortened so no mouth plane is crossed and crossed back within the step.

    For a hole whose mouth the tip circle could reach during the step (the tip centre's
    lateral distance from the axis minus D(h) within the mouth radius) and whose plane it
    could reach (height minus D(h) ≤ 0): the height z(τ) ≥ z + τ·(z'_lo) − ½Aτ² stays positive
    up to one root, and z'(τ) ≤ z'_hi + Aτ stays negative (a monotone descent, crossed at
    most once) up to another; the step may go to the later of the two. z' of the tip centre is
    the axis component of its velocity, ± the hand error's blend.
    """
    if not mouth_radii.size:
        return h
    curvature = flight.curvature
    moved = h * flight.speed + 0.5 * curvature * h * h
    risky = (axial > 0.0) & (axial - moved <= 0.0) & (lateral - moved <= mouth_radii)
    if not risky.any():
        return h
    index = np.flatnonzero(risky)
    tip = np.asarray(pose.translation)
    velocity = flight.velocity + cross3(flight.omega, tip - flight.origin)
    rates = mouths.axes[index] @ velocity  # the tip centre's height rate, less the blend
    above = safe_steps(axial[index], -(rates - flight.blend), curvature)
    falling = rates + flight.blend
    with np.errstate(divide="ignore"):
        monotone = np.where(falling < 0.0, -falling / curvature if curvature > 0.0 else np.inf, 0.0)
    return min(h, float(np.min(np.maximum(above, monotone))))


def _crossing_flight(hole: HoleSite, flight: PinFlight, lo: float, hi: float) -> float:
    """The s in [lo, hi] where the tip crosses the mouth plane (:func:`event_crossing`).

    The tip's height above the mouth is > 0 at ``lo`` and ≤ 0 at ``hi``; the bracket ends as
    narrow as the reference path's 40 bisections (:func:`_crossing`) make it.
    """
    origin = hole.world_from_hole.translation
    axis = hole.axis
    return event_crossing(lambda s: float(axis @ (flight.tip(s) - origin)), lo, hi)


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
    flight: PinFlight | None = None,
) -> PinContact | None:
    """The first contact of the pin over s ∈ [start, end], or None (see the module docstring).

    With a ``flight`` (the pin's motion with its bounds, :class:`~synth.replay.bounds.PinFlight`)
    the fast path; without, the reference path, on ``pose_at`` and the constant ``speed``
    [m per unit s] that bounds the speed of every point of the pin along the path.

    With ``friction`` (μ) a capture at a tilt that wedges the pin is a ``wedge`` contact.
    ``clearance`` [m] is the distance that counts as touching. A pin that starts closer than
    ``clearance`` to an obstacle (it rests where a previous motion stopped it) counts as
    touching that obstacle only below half its starting distance.
    """
    if flight is not None:
        return _first_contact_flight(
            pin_model, flight, obstacles, holes, start, end, clearance, friction
        )
    pin_ = PinGeometry(pin_model)
    targets = [Target(o) for o in obstacles]
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
            if captures(hole, pin_model, placement, _mu(friction)):
                axis = hole.axis
                point = hole.world_from_hole.translation.copy()
                kind = _entry(hole, pin_model, placement, friction)
                return PinContact(crossing, kind, hole.owner, hole, axis, point, np.zeros(3), 0.0)
        s, pose = s_next, pose_next
    raise RuntimeError("pin contact search did not converge")


def _crossing(hole: HoleSite, pose_at: PoseAt, lo: float, hi: float) -> float:
    """The s in [lo, hi] where the tip crosses the mouth plane (bisection on the axial height)."""
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        if tip_placement(hole, pose_at(mid)).axial > 0.0:
            lo = mid
        else:
            hi = mid
    return hi


def _mu(friction: float | None) -> float:
    """The task's friction μ for the rim's capture test (the default μ when wedging is off)."""
    return DEFAULT_FRICTION if friction is None else friction


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
    pin_: PinGeometry,
    pose: pin.SE3,
    s: float,
    target: Target,
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
        inside = placement.axial <= hole.mouth_radius
        if inside and captures(hole, pin_.model, placement, _mu(friction)):
            kind = _entry(hole, pin_.model, placement, friction)
            return PinContact(s, kind, name, hole, hole.axis, point, local, d)
    # Coal's normal points from the pin to the obstacle; the surface normal is opposite
    norm = norm3(normal) if np.all(np.isfinite(normal)) else 0.0
    outward = -normal / norm if norm > 1e-12 else np.zeros(3)
    if not (np.all(np.isfinite(point)) and np.all(np.isfinite(local))):
        point, local = pose.translation.copy(), np.zeros(3)  # degenerate: use the tip
    return PinContact(s, "surface", name, None, outward, point, local, d)
