"""Object meshes for collision: a box with drilled, chamfered holes; a pin with a tapered tip.

The replay lets geometry decide what the pin touches (design card: "the replay is the
referee"), so it needs solids of the seed's parts: the box with hole BH1 and the pin PIN1 of
§4.8 (seed L2562–2590), plus plain blocks for racks and tables. Dimensions are SI floats [m].

Every solid of revolution is built by :func:`trimesh.creation.revolve` of a closed profile
with ``segments`` sections, starting at angle 0 (a vertex on the +x half-plane). Its cross
sections are regular n-gons *inscribed* in the true circles, so every such volume is the
continuous one times the inscribed-polygon area ratio

    k(n) = n/(2π) · sin(2π/n)        (k(48) = 0.99715),

exactly — also for cone frusta, whose polygonal cross sections stay similar. Holes are cut
with the ``manifold3d`` boolean engine (the one trimesh uses, called here in float64), which
returns watertight (2-manifold) meshes.

Meshes are cached (``functools.lru_cache`` on the normalised, hashable arguments); each call
returns a fresh, writable copy, so a caller may transform its mesh into the world frame with
``apply_transform`` without corrupting the cache. The cached masters are read-only.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from functools import lru_cache

import manifold3d
import numpy as np
import trimesh

__all__ = [
    "DEFAULT_SEGMENTS",
    "Hole",
    "block",
    "box_with_holes",
    "hole_problem",
    "inscribed_area_ratio",
    "pin",
]

DEFAULT_SEGMENTS = 48
"""Sections of every revolved surface; a multiple of 4 puts vertices on the ±x and ±y axes."""

Hole = tuple[float, float, float, float, float]
"""``(x, y, diameter, depth, chamfer_width)`` [m]: a hole drilled along -z from the top face."""

_CACHE_SIZE = 128


def inscribed_area_ratio(segments: int) -> float:
    """Area of a regular ``segments``-gon inscribed in a circle over the circle's: n/(2π)·sin(2π/n).

    Volume of every revolved solid here over its continuous counterpart (see module docstring).
    """
    return segments / (2.0 * math.pi) * math.sin(2.0 * math.pi / segments)


# ---------------------------------------------------------------- public constructors


def block(size_xyz: Sequence[float]) -> trimesh.Trimesh:
    """Plain box of extents ``size_xyz`` [m] (racks, tables).

    Frame: origin at the centre of the bottom face, z up; the box spans
    [-sx/2, sx/2] × [-sy/2, sy/2] × [0, sz].
    """
    return _block_cached(_size(size_xyz)).copy()


def box_with_holes(
    size_xyz: Sequence[float],
    holes: Iterable[Sequence[float]] = (),
    segments: int = DEFAULT_SEGMENTS,
) -> trimesh.Trimesh:
    """Box of extents ``size_xyz`` [m] with chamfered holes drilled from its top face.

    Frame as :func:`block`: origin at the centre of the bottom face, z up, top face at z = sz.
    Each hole is ``(x, y, diameter, depth, chamfer_width)`` [m] in the box frame; its axis is +z
    through (x, y), its mouth on the top face. The bore has radius r = diameter/2 from
    z = sz - depth to z = sz - w; the chamfer is a 45° countersink of radial width w, so the
    mouth has radius r + w at z = sz. A hole with depth ≥ sz goes through the box.

    Removed volume per blind hole (continuous; the mesh removes k(n) times it, see
    :func:`inscribed_area_ratio`):

        V_hole = π r² (depth - w) + (π w / 3) (r² + r (r + w) + (r + w)²).

    Raises ``ValueError`` for non-positive or non-finite sizes, a chamfer not shallower than
    the hole, or a mouth not strictly inside the top face.
    """
    size = _size(size_xyz)
    normalised = tuple(_hole(size, i, h) for i, h in enumerate(holes))
    return _box_with_holes_cached(size, normalised, _segments(segments)).copy()


def pin(
    length: float,
    shaft_diameter: float,
    tip_taper_length: float,
    tip_radius: float,
    segments: int = DEFAULT_SEGMENTS,
) -> trimesh.Trimesh:
    """Pin with a tapered tip: a cone frustum, then the cylindrical shaft [m].

    Frame: origin at the centre of the tip face, z along the pin from the tip to the head. The
    radius grows linearly from ``tip_radius`` at z = 0 to b = shaft_diameter/2 at
    z = ``tip_taper_length``, then stays b up to z = ``length``. ``tip_radius`` = 0 gives a
    pointed tip, ``tip_taper_length`` = 0 a blunt one. Continuous volume (the mesh has k(n)
    times it):

        V = (π h / 3) (a² + a b + b²) + π b² (length - h),   a = tip_radius, h = taper length.
    """
    values = {
        "length": length,
        "shaft_diameter": shaft_diameter,
        "tip_taper_length": tip_taper_length,
        "tip_radius": tip_radius,
    }
    for name, value in values.items():
        if not math.isfinite(value) or value < 0.0:
            raise ValueError(f"pin {name} must be a finite length ≥ 0 [m], got {value!r}")
    if length <= 0.0 or shaft_diameter <= 0.0:
        raise ValueError(
            f"pin length and shaft_diameter must be > 0 [m], got {length!r}, {shaft_diameter!r}"
        )
    if tip_radius > shaft_diameter / 2.0:
        raise ValueError(
            f"pin tip_radius {tip_radius!r} exceeds the shaft radius {shaft_diameter / 2.0!r}"
        )
    if tip_taper_length > length:
        raise ValueError(f"pin tip_taper_length {tip_taper_length!r} exceeds length {length!r}")
    key = (float(length), float(shaft_diameter), float(tip_taper_length), float(tip_radius))
    return _pin_cached(*key, _segments(segments)).copy()


# ---------------------------------------------------------------- validation


def _size(size_xyz: Sequence[float]) -> tuple[float, float, float]:
    values = tuple(float(v) for v in size_xyz)
    if len(values) != 3 or not all(math.isfinite(v) and v > 0.0 for v in values):
        raise ValueError(f"size_xyz must be three finite lengths > 0 [m], got {size_xyz!r}")
    return values[0], values[1], values[2]


def _segments(segments: int) -> int:
    if not isinstance(segments, int) or segments < 8 or segments % 4:
        raise ValueError(f"segments must be a multiple of 4 and ≥ 8, got {segments!r}")
    return segments


def hole_problem(size: tuple[float, float, float], hole: Sequence[float]) -> str | None:
    """Why ``hole`` (x, y, diameter, depth, chamfer_width) [m] cannot be drilled, or None.

    The rule :func:`box_with_holes` enforces: finite numbers, diameter and depth > 0, chamfer
    ≥ 0 and shallower than the hole (a 45° chamfer of width w is w deep), and the mouth, of
    radius diameter/2 + w, strictly inside the ``size`` box's top face.
    """
    values = tuple(float(v) for v in hole)
    if len(values) != 5 or not all(math.isfinite(v) for v in values):
        return (
            f"must be five finite numbers (x, y, diameter, depth, chamfer_width) [m], got {hole!r}"
        )
    x, y, diameter, depth, chamfer = values
    if diameter <= 0.0 or depth <= 0.0 or chamfer < 0.0:
        return f"diameter and depth must be > 0 and chamfer_width ≥ 0 [m], got {hole!r}"
    if chamfer >= depth:
        return (
            f"a 45° chamfer of width {chamfer!r} needs a hole deeper than that, got depth {depth!r}"
        )
    mouth = diameter / 2.0 + chamfer
    sx, sy, _ = size
    if abs(x) + mouth >= sx / 2.0 or abs(y) + mouth >= sy / 2.0:
        cm = 100.0  # a task's sizes are read in cm far more often than in m
        return (
            f"the mouth (radius {cm * mouth:.4g} cm at ({cm * x:.4g}, {cm * y:.4g}) cm) must "
            f"lie strictly inside the {cm * sx:.4g} × {cm * sy:.4g} cm top face"
        )
    return None


def _hole(size: tuple[float, float, float], i: int, hole: Sequence[float]) -> Hole:
    problem = hole_problem(size, hole)
    if problem is not None:
        separator = " " if problem.startswith("must") else ": "
        raise ValueError(f"holes[{i}]{separator}{problem}")
    x, y, diameter, depth, chamfer = (float(v) for v in hole)
    return x, y, diameter, depth, chamfer


# ---------------------------------------------------------------- cached builders


def _freeze(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """Make a cached master read-only, so only copies are ever changed."""
    mesh.vertices.flags.writeable = False
    mesh.faces.flags.writeable = False
    return mesh


def _check_solid(mesh: trimesh.Trimesh, what: str) -> trimesh.Trimesh:
    if not (mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0.0):
        raise RuntimeError(f"mesh construction for {what} did not give a closed solid")
    return mesh


def _box(size: tuple[float, float, float]) -> trimesh.Trimesh:
    box = trimesh.creation.box(extents=size)
    box.apply_translation((0.0, 0.0, size[2] / 2.0))
    return box


@lru_cache(maxsize=_CACHE_SIZE)
def _block_cached(size: tuple[float, float, float]) -> trimesh.Trimesh:
    return _freeze(_check_solid(_box(size), f"block {size}"))


def _revolve(profile: np.ndarray, segments: int) -> trimesh.Trimesh:
    """The solid of revolution of a (radius, z) profile [m] about z, built in millimetres.

    trimesh drops the triangles of a revolved mesh whose area is below its merge tolerance,
    1e-8 in the mesh's units: in metres that is 0.01 mm², and the thin triangles by the axis of
    a 2 mm hole with 48 sections fell below it, leaving the cutter open (a property test found
    it: diameter 2.19 mm, 1.09 mm deep, on a 10 cm block). In millimetres they are 10⁶ larger.
    """
    mesh = trimesh.creation.revolve(profile * 1000.0, sections=segments)
    mesh.apply_scale(1e-3)
    return mesh


def _hole_cutter(size_z: float, hole: Hole, segments: int) -> trimesh.Trimesh:
    """Solid removed by one hole: bore, 45° countersink, continued past the faces it opens."""
    x, y, diameter, depth, chamfer = hole
    r = diameter / 2.0
    overshoot = r + chamfer  # [m] margin past the top (and the bottom of a through hole)
    z_top = size_z
    z_bottom = -overshoot if depth >= size_z else size_z - depth
    # (radius, z) profile, counter-clockwise; the cone keeps its 45° slope through the top
    # face (and a plain bore stays straight) so that the cutter crosses every face of the box
    # transversally: no coplanar faces for the boolean.
    if chamfer > 0.0:
        mouth = [(r, z_top - chamfer), (r + chamfer + overshoot, z_top + overshoot)]
    else:
        mouth = [(r, z_top + overshoot)]
    profile = np.array([(0.0, z_bottom), (r, z_bottom), *mouth, (0.0, z_top + overshoot)])
    cutter = _revolve(profile, segments)
    cutter.apply_translation((x, y, 0.0))
    return _check_solid(cutter, f"hole cutter {hole}")


@lru_cache(maxsize=_CACHE_SIZE)
def _box_with_holes_cached(
    size: tuple[float, float, float], holes: tuple[Hole, ...], segments: int
) -> trimesh.Trimesh:
    box = _box(size)
    if holes:
        cutters = [_hole_cutter(size[2], hole, segments) for hole in holes]
        box = _difference(box, cutters)
    return _freeze(_check_solid(box, f"box {size} with holes {holes}"))


def _to_manifold(mesh: trimesh.Trimesh) -> manifold3d.Manifold:
    solid = manifold3d.Manifold(
        mesh=manifold3d.Mesh64(
            vert_properties=np.ascontiguousarray(mesh.vertices, dtype=np.float64),
            tri_verts=np.ascontiguousarray(mesh.faces, dtype=np.uint64),
        )
    )
    if solid.status() != manifold3d.Error.NoError:
        raise RuntimeError(f"manifold3d rejected a mesh: {solid.status()}")
    return solid


def _difference(body: trimesh.Trimesh, cutters: Sequence[trimesh.Trimesh]) -> trimesh.Trimesh:
    """Boolean ``body`` minus the union of ``cutters`` with manifold3d in double precision.

    This is what ``trimesh.boolean.difference(..., engine="manifold")`` does, except that
    trimesh (5.2) hands manifold3d float32 vertices, which moves every vertex by up to ~4 nm
    on a 7 cm part; ``Mesh64`` keeps the float64 coordinates.
    """
    result = _to_manifold(body) - manifold3d.Manifold.batch_boolean(
        [_to_manifold(c) for c in cutters], manifold3d.OpType.Add
    )
    if result.status() != manifold3d.Error.NoError:
        raise RuntimeError(f"manifold3d boolean failed: {result.status()}")
    out = result.to_mesh64()
    return trimesh.Trimesh(
        vertices=np.asarray(out.vert_properties, dtype=np.float64)[:, :3],
        faces=np.asarray(out.tri_verts, dtype=np.int64),
        process=False,
    )


@lru_cache(maxsize=_CACHE_SIZE)
def _pin_cached(
    length: float, shaft_diameter: float, taper: float, tip_radius: float, segments: int
) -> trimesh.Trimesh:
    b = shaft_diameter / 2.0
    points = [(0.0, 0.0), (tip_radius, 0.0), (b, taper), (b, length), (0.0, length)]
    # drop the repeated profile points of a pointed (a = 0) or blunt (h = 0) tip
    profile = [p for i, p in enumerate(points) if i == 0 or p != points[i - 1]]
    mesh = _revolve(np.array(profile), segments)
    return _freeze(_check_solid(mesh, f"pin {(length, shaft_diameter, taper, tip_radius)}"))
