"""Where a pin's tip is relative to a hole, whether the hole captures it, and where it seats.

Pure geometry of the true parts: the hole's bore, chamfer and mouth, the pin's tip, taper and
shaft. Nothing here reads the planner's insertion parameters (Δr_ok, Δθ_ok and their closed
forms in :mod:`synth.models.insertion` are what the *planner* believes; the seed measured them
on its real parts, seed §4.2 L1990–2010, and the replay measures its simulated parts instead).

**Tip placement.** With the hole's mouth frame M (z out of the hole) and the pin frame P (origin
at the tip centre, z from the tip to the head), ``M⁻¹ P`` gives the tip centre's distance from
the hole axis (``lateral``), its height above the mouth plane (``axial``, negative inside), the
angle between the two axes (``tilt``; a pin going in tip first has its z along the hole's z) and
the azimuth of the pin's axis about the hole's, from the direction of the tip centre (``lean``:
0 when the head leans away from the hole axis, π towards it). Both parts being solids of
revolution, these four numbers place the pin completely.

**Capture** (:func:`entry_contact`, :func:`captures`). In M the part's surface around the hole
is the height field (r the bore's radius, w the 45° chamfer's width, r_m = r + w the mouth's)

    S(ρ) = 0 (the face, ρ ≥ r_m),   ρ − r_m (the chamfer, r ≤ ρ < r_m),   −depth (ρ < r).

The pin is let down along the hole's axis from its placement, as the approach moves it; it
first touches the part at the drop ``s* = min_{p ∈ pin} (z_p − S(ρ_p))``, and where that minimum
lies decides:

* on the chamfer or in the bore: **captured** — the 45° cone pushes the pin towards the axis;
* on the face, ρ > r_m: not captured, the pin stands on the surface;
* on the mouth's rim (ρ = r_m, the edge between face and chamfer; a drop within 10⁻⁸ m of the
  rim's counts as the rim's): captured when the rim's reaction, along the pin's outward normal
  n there, pushes it inwards more than μ times as hard as it holds it up,
  ``n·ρ̂ / (−n·ẑ) > μ`` (Coulomb, μ the task's friction: the pin's own taper then leads it in,
  Whitney's r_shaft − r_tip), else not (a flat tip face lying across the rim stays there). On
  a smooth part of the pin n is its surface normal; on one of its edges (the tip rim, the
  taper's top) crossing the rim, the two edges' common normal; on an edge (nearly) tangent to
  the rim any normal of the edge's cone can carry the load and the least steep one is taken.

The minimum is found exactly, not sampled over the solid: the pin is the convex hull of its tip
rim (radius a at the tip), the taper's top circle (the shaft radius b, a taper length h up) and
the head rim. On each of the three regions of ρ the function to minimise is linear or concave
(z, or z − ρ + r_m) over a convex body cut by the cylinders ρ = r and ρ = r_m, so its minimum
lies on one of the three rims, or on the pin's lower envelope L(x, y) over the circles ρ = r
(the chamfer's lower edge: z = L − S = L + w) and ρ = r_m (the rim: L). L is exact (a vertical
line against the frustum and the cylinder: one quadratic each); the minima over a circle are
taken on 720 angles and refined four times around the best (to 1.3·10⁻⁷ rad, under 1 nm on
the seed's mouth).

For an upright pin this is Whitney's lead condition ``lateral + a ≤ r_m`` — the tip rim lands
on the chamfer rather than the flat tip face across the rim — as long as the taper is less
steep than the chamfer ((b − a)/h < 1; the seed's pin: 0.55). The planner's closed forms for
Δr_ok and Δθ_ok (:mod:`synth.models.insertion`) reduce to it upright; tilted, the drop decides
(``tests/test_capture_geometry.py`` compares it with Coal on the meshes: it agrees with the
closed form ``lateral + a cos θ ≤ r_m, θ ≤ atan((r_m − a)/(h + w))`` up to 3° of tilt, and
captures pins tilted 10°–40° that the closed form refused, whose tip edge reaches the chamfer
or whose taper reaches the rim from beyond the upright lead). A pin arriving head
first (tilt ≥ 90°) is never captured, which is why the planner refuses such insertions. A
captured pin may still wedge at its two-point contact (:mod:`synth.replay.wedging`, decided by
:mod:`synth.replay.contact`).

**Seat.** A captured pin slides along the hole axis until it is stopped: by the hole's bottom
when its shaft fits the bore (depth = hole depth, or the pin's length if the hole is deeper),
otherwise where its taper wedges in the bore or its tip in the chamfer.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.models.spec import DEFAULT_FRICTION
from synth.models.workcell import HoleSite, PinModel
from synth.vec3 import cross3, norm3

__all__ = [
    "EntryContact",
    "TipPlacement",
    "captures",
    "entry_contact",
    "inserted_depth",
    "seat_depth",
    "seated_pose",
    "tip_placement",
]

FloatArray = NDArray[np.float64]

_ANGLES = 720
"""Angles per circle for the minima over a circle (then refined, :data:`_LEVELS`)."""
_REFINE = 33
_LEVELS = 4
"""Refinements around the best angle: the step ends 16⁻⁴ of a grid step (1.3·10⁻⁷ rad)."""
_TANGENT = 1e-2
"""[1] sin of the angle below which an edge of the pin and the rim count as tangent."""
_TIE = 1e-8
"""[m] a drop onto the face or into the mouth within this of the rim's is a rim contact."""
_ZHAT = np.array([0.0, 0.0, 1.0])
"""ẑ, the mouth frame's axis."""


@dataclass(frozen=True)
class TipPlacement:
    """The pin's tip relative to a hole: ``lateral``, ``axial`` [m], ``tilt``, ``lean`` [rad].

    See the module docstring; ``lean`` 0 tilts the head away from the hole axis, π towards it.
    """

    lateral: float
    axial: float
    tilt: float
    lean: float = 0.0

    def local(self) -> tuple[FloatArray, FloatArray]:
        """Tip centre [m] and pin axis (unit) in the mouth frame, the tip centre on +x."""
        c = np.array([self.lateral, 0.0, self.axial])
        st = math.sin(self.tilt)
        u = np.array([st * math.cos(self.lean), st * math.sin(self.lean), math.cos(self.tilt)])
        return c, u


def tip_placement(hole: HoleSite, pin_pose: pin.SE3) -> TipPlacement:
    """Tip centre and pin axis of a pin at world pose ``pin_pose`` in the hole's mouth frame."""
    local = hole.world_from_hole.actInv(pin_pose)
    c = local.translation
    u = local.rotation[:, 2]
    cos_tilt = min(max(float(u[2]), -1.0), 1.0)
    lateral = float(math.hypot(c[0], c[1]))
    lean = 0.0
    if lateral > 0.0 and math.hypot(u[0], u[1]) > 0.0:
        lean = math.remainder(math.atan2(u[1], u[0]) - math.atan2(c[1], c[0]), 2.0 * math.pi)
    return TipPlacement(lateral, float(c[2]), math.acos(cos_tilt), lean)


@dataclass(frozen=True)
class EntryContact:
    """Where a pin let down along the hole's axis first touches the part (module docstring).

    ``where``: ``mouth`` (chamfer or bore), ``rim`` or ``face``; None if no point of the pin
    lies over the mouth or it comes head first. ``face``, ``mouth`` and ``rim`` [m] are how far
    it would fall onto each (+inf: never; all +inf when ``where`` is None, not computed);
    ``slope`` [1] is the rim's push inwards per push up where the pin would touch it
    (:meth:`_Solid.rim_slope`), ``corner`` whether it would touch with one of its edges.
    """

    where: Literal["mouth", "rim", "face"] | None
    face: float = math.inf
    mouth: float = math.inf
    rim: float = math.inf
    slope: float = 0.0
    corner: bool = False

    @property
    def drop(self) -> float:
        """How far the pin falls before it touches [m] (+inf: it touches nothing)."""
        return min(self.face, self.mouth, self.rim)


class _Solid:
    """The pin in the mouth frame: tip centre ``c``, axis ``u``, profile a → b over h, length."""

    def __init__(self, model: PinModel, c: FloatArray, u: FloatArray) -> None:
        self.c, self.u = c, u
        self.a, self.b = model.radius_at(0.0), model.radius
        self.h, self.length = model.shape.tip_taper_length, model.length
        e1 = cross3(_ZHAT, u)
        norm = norm3(e1)
        e1 = e1 / norm if norm > 1e-12 else np.array([1.0, 0.0, 0.0])
        self.e1, self.e2 = e1, cross3(u, e1)

    def rims(self) -> list[tuple[float, float]]:
        """(height along the axis, radius) of the tip rim, the taper's top and the head rim."""
        return [(0.0, self.a), (self.h, self.b), (self.length, self.b)]

    def rings(
        self, heights: FloatArray, radii: FloatArray, cos: FloatArray, sin: FloatArray
    ) -> FloatArray:
        """Points of rim circles, row k at angles ψ (cos ψ, sin ψ) on circle (h_k, ρ_k).

        Shape ``cos.shape + (3,)``: c + h·u + ρ·(cos ψ·e₁ + sin ψ·e₂).
        """
        ring = cos[..., None] * self.e1 + sin[..., None] * self.e2
        base = self.c + heights[:, None] * self.u  # c + h·u, one row per circle
        return np.asarray(base[:, None, :] + radii[:, None, None] * ring)

    def lowest(self, x: FloatArray, y: FloatArray) -> FloatArray:
        """L(x, y): the lowest z of the pin on each vertical line (+inf where it misses).

        The shaft's and the taper's first points are found in one pass of
        :func:`_first_inside` (the two problems side by side); any shape of ``x`` and ``y``.
        """
        shape = x.shape
        x, y = x.reshape(-1), y.reshape(-1)
        n = x.size
        d0 = np.stack([x - self.c[0], y - self.c[1], np.full_like(x, -self.c[2])], axis=1)
        a0 = d0 @ self.u  # height along the pin axis at t = 0; it grows as a1·t
        a1 = float(self.u[2])
        quad = 1.0 - a1 * a1
        lin = 2.0 * (d0[:, 2] - a0 * a1)
        const = (
            np.einsum("ij,ij->i", d0, d0) - a0 * a0
        )  # radial distance² = quad t² + lin t + const
        if self.h <= 0.0:
            shaft = _first_inside(
                quad, lin, const - self.b**2, (self.h - a0) / a1, (self.length - a0) / a1
            )
            return shaft.reshape(shape)
        k = (self.b - self.a) / self.h  # radius a + k·(height) on the taper
        r0, r1 = self.a + k * a0, k * a1
        first = _first_inside(
            np.concatenate([np.full(n, quad), np.full(n, quad - r1 * r1)]),
            np.concatenate([lin, lin - 2.0 * r0 * r1]),
            np.concatenate([const - self.b**2, const - r0 * r0]),
            np.concatenate([(self.h - a0) / a1, -a0 / a1]),
            np.concatenate([(self.length - a0) / a1, (self.h - a0) / a1]),
        )
        return np.minimum(first[:n], first[n:]).reshape(shape)

    def normals(self, point: FloatArray, rim_tangent: FloatArray) -> tuple[list[FloatArray], bool]:
        """The pin's outward unit normals at a ``point`` of its surface touching the hole's rim.

        On a smooth part, one: the tip face's −u, the taper's (e_r − k u)/√(1 + k²), the
        shaft's e_r (e_r the radial direction about the pin axis). On one of its edges (the tip
        rim, the taper's top) crossing the rim, the two edges' common normal
        ± (u × e_r) × ``rim_tangent``, kept within the edge's normal cone; when the edge is
        (nearly) tangent to the rim, the two ends of that cone, any normal between them being
        possible. The flag says whether the point is on an edge.
        """
        d = point - self.c
        height = float(d @ self.u)
        radial = d - height * self.u
        rho = norm3(radial)
        e_r = radial / rho if rho > 0.0 else self.e1
        k = (self.b - self.a) / self.h if self.h > 0.0 else 0.0
        taper = (e_r - k * self.u) / math.hypot(1.0, k)
        near = 1e-8  # [m] on an edge
        if abs(height) <= near and abs(rho - self.a) <= near:
            cone = (-self.u, taper if self.h > 0.0 else e_r)
        elif self.h > 0.0 and abs(height - self.h) <= near and abs(rho - self.b) <= near:
            cone = (taper, e_r)
        elif height <= near:
            return [-self.u], False
        else:
            return [np.asarray(taper if height < self.h else e_r)], False
        common = cross3(cross3(self.u, e_r), rim_tangent)
        norm = norm3(common)
        if norm <= _TANGENT:
            return list(cone), True
        common = common / norm
        if common @ (cone[0] + cone[1]) < 0.0:
            common = -common
        # within the cone spanned by its two faces' normals, else the nearer of them
        span = float(np.arccos(np.clip(cone[0] @ cone[1], -1.0, 1.0)))
        to0 = float(np.arccos(np.clip(common @ cone[0], -1.0, 1.0)))
        to1 = float(np.arccos(np.clip(common @ cone[1], -1.0, 1.0)))
        if to0 <= span + 1e-12 and to1 <= span + 1e-12:
            return [np.asarray(common)], True
        return [np.asarray(cone[0] if to0 < to1 else cone[1])], True

    def rim_slope(self, radius: float, phi: float, height: float) -> tuple[float, bool]:
        """The rim's push inwards per push up on a pin touching it at angle ``phi`` [1].

        ``n·ρ̂ / (−n·ẑ)`` for the pin's outward normal n there (:meth:`normals`; the least of
        them when several can carry the load: the pin rests if it can): positive when the
        rim's reaction, along −n, drives the pin towards the hole axis. Also whether the pin
        touches with one of its edges.
        """
        out = np.array([math.cos(phi), math.sin(phi), 0.0])
        tangent = np.array([-math.sin(phi), math.cos(phi), 0.0])
        candidates, corner = self.normals(
            np.array([radius * out[0], radius * out[1], height]), tangent
        )
        slopes = []
        for n in candidates:
            down, inwards = -float(n[2]), float(n @ out)
            slopes.append(inwards / down if down > 1e-12 else math.copysign(math.inf, inwards))
        return min(slopes), corner


def _first_inside(
    q2: float | FloatArray, q1: FloatArray, q0: FloatArray, lo: FloatArray, hi: FloatArray
) -> FloatArray:
    """The least t in [lo, hi] with q2 t² + q1 t + q0 ≤ 0, per entry (+inf if none).

    Either lo itself, or the first root of the quadratic above lo (the set is an interval on a
    convex piece of the pin, so its least point is one of them).
    """
    q2 = np.broadcast_to(np.asarray(q2, dtype=float), q1.shape)
    out = np.full(q1.shape, np.inf)
    scale = np.abs(q0) + np.abs(q1) * np.abs(lo) + np.abs(q2) * lo * lo + 1e-300
    at_lo = q2 * lo * lo + q1 * lo + q0 <= 1e-12 * scale
    out[at_lo & (lo <= hi)] = lo[at_lo & (lo <= hi)]
    with np.errstate(divide="ignore", invalid="ignore"):
        linear = np.abs(q2) <= 1e-12
        disc = q1 * q1 - 4.0 * q2 * q0
        root = np.sqrt(np.maximum(disc, 0.0))
        big = -0.5 * (q1 + np.where(q1 >= 0.0, root, -root))
        r1 = np.where(linear, -q0 / q1, big / q2)
        r2 = np.where(linear, np.inf, q0 / big)
        real = linear | (disc >= 0.0)
        first = np.fmin(r1, r2)
        second = np.fmax(r1, r2)
        for r in (second, first):  # the least root that lies in (lo, hi] wins
            ok = real & ~at_lo & np.isfinite(r) & (r > lo) & (r <= hi)
            out[ok] = r[ok]
    return out


def _refine(
    evaluate: Callable[[FloatArray], FloatArray], values: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Per row, the minimum over φ of a function, from its ``values`` on the grid, refined.

    Row k of ``values`` is function k on :data:`_GRID`; ``evaluate`` takes a matrix of angles,
    row k for function k, and returns their values. Each row's best grid angle is refined
    :data:`_LEVELS` times on :data:`_REFINE` angles about the best so far, all rows in step.
    Returns (minima, φ); +inf and 0 for a row nowhere finite on the grid.
    """
    rows = np.arange(values.shape[0])
    i = np.argmin(values, axis=1)
    best, where = values[rows, i].copy(), _GRID[i].copy()
    finite = np.isfinite(best)
    best[~finite], where[~finite] = math.inf, 0.0
    if not finite.any():
        return best, where
    step = 2.0 * math.pi / _ANGLES
    for _ in range(_LEVELS):
        phi = np.linspace(where - step, where + step, _REFINE, axis=1)
        v = evaluate(phi)
        j = np.argmin(v, axis=1)
        lower = finite & (v[rows, j] < best)
        best[lower], where[lower] = v[rows, j][lower], phi[rows, j][lower]
        step = 2.0 * step / (_REFINE - 1)
    return best, where


_GRID = np.linspace(0.0, 2.0 * math.pi, _ANGLES, endpoint=False)
_GRID_COS, _GRID_SIN = np.cos(_GRID), np.sin(_GRID)


def entry_contact(hole: HoleSite, pin_model: PinModel, placement: TipPlacement) -> EntryContact:
    """Where the pin, let down along the hole's axis, first touches the part (module docstring).

    Eight minima over a circle, found together (:func:`_refine`): each of the three rims'
    drop onto the face (ρ > r_m) and into the mouth (the chamfer, z − ρ + r_m, or the bottom,
    z + depth), and the lower envelope over the chamfer's lower edge (ρ = r, + w) and over the
    mouth's rim (ρ = r_m). A rim's minimum counts only where its grid minimum is below what the
    rims before it found (the order of the module's proof).
    """
    if placement.tilt >= 0.5 * math.pi:
        return EntryContact(None)  # head first or lying down: no tip to enter with
    r, w, r_m, depth = hole.radius, hole.chamfer, hole.mouth_radius, hole.depth
    reach = pin_model.length * math.sin(placement.tilt) + max(
        pin_model.radius_at(0.0), pin_model.radius
    )
    if placement.lateral - reach >= r_m:
        return EntryContact(None)  # no point of the pin above the mouth
    c, u = placement.local()
    solid = _Solid(pin_model, c, u)
    rims = solid.rims()
    heights = np.array([h for h, _ in rims] * 2)  # rows 0–2 onto the face, 3–5 into the mouth
    radii = np.array([radius for _, radius in rims] * 2)
    into = np.arange(6) >= 3
    envelope_radii = np.array([r, r_m])  # rows 6, 7: the chamfer's lower edge, the mouth's rim
    lifts = np.array([w, 0.0])

    def drops(p: FloatArray) -> FloatArray:
        """Rows 0–5's drops: onto the face (ρ > r_m), or into the mouth for rows 3–5."""
        rho, z = np.hypot(p[..., 0], p[..., 1]), p[..., 2]
        inside = np.where(rho < r, z + depth, z - rho + r_m)
        mouth = np.where(rho < r_m, inside, np.inf)
        return np.where(into[:, None], mouth, np.where(rho > r_m, z, np.inf))

    def evaluate(psi: FloatArray) -> FloatArray:
        cos, sin = np.cos(psi), np.sin(psi)
        rim_drops = drops(solid.rings(heights, radii, cos[:6], sin[:6]))
        around = envelope_radii[:, None] * cos[6:], envelope_radii[:, None] * sin[6:]
        return np.vstack([rim_drops, solid.lowest(*around) + lifts[:, None]])

    # on the grid each rim's points serve both its drops, and every row's angles are the same
    points = solid.rings(heights[:3], radii[:3], _GRID_COS[None, :], _GRID_SIN[None, :])
    both = np.concatenate([points, points])
    around = envelope_radii[:, None] * _GRID_COS, envelope_radii[:, None] * _GRID_SIN
    grid = np.vstack([drops(both), solid.lowest(*around) + lifts[:, None]])
    minima, phis = _refine(evaluate, grid)
    face = mouth = math.inf
    for k in range(3):
        if grid[k].min() < face:
            face = min(face, float(minima[k]))
        if grid[3 + k].min() < mouth:
            mouth = min(mouth, float(minima[3 + k]))
    mouth = min(mouth, float(minima[6]))
    rim, phi = float(minima[7]), float(phis[7])
    slope, corner = solid.rim_slope(r_m, phi, rim) if math.isfinite(rim) else (0.0, False)
    where: Literal["mouth", "rim", "face"] | None
    if not math.isfinite(min(face, mouth, rim)):
        where = None
    elif min(face, mouth) < rim - _TIE:  # strictly inside a region, away from the rim
        where = "mouth" if mouth < face else "face"
    else:  # the lowest point over either region is the rim itself
        where = "rim"
    return EntryContact(where, face, mouth, rim, slope, corner)


def captures(
    hole: HoleSite,
    pin_model: PinModel,
    placement: TipPlacement,
    friction: float = DEFAULT_FRICTION,
) -> bool:
    """Whether the hole captures a pin at ``placement`` (module docstring, "Capture").

    True when the pin's first contact is on the chamfer or in the bore, or on the mouth's rim
    with the rim pushing it inwards more than ``friction`` (μ) times as hard as it holds it up.
    """
    contact = entry_contact(hole, pin_model, placement)
    if contact.where == "mouth":
        return True
    return contact.where == "rim" and contact.slope > friction


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
