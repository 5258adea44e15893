"""The workcell's solids: a table, boxes with chamfered holes, racks, fixtures and pins.

Built from the task's shapes and placed at any set of poses: the *true* poses of a replay trial
(:mod:`synth.replay.truth`) or the nominal ones the planner believes
(:class:`NominalPoses`, for its gross-motion check, :mod:`synth.strategies.clearance`):

* the table: a slab whose top face is the world plane z = 0 (the world frame is the work
  station, :data:`synth.models.spec.WORLD`), ``TABLE_THICKNESS`` thick, reaching
  ``TABLE_MARGIN`` past every task frame and the arm's base;
* every ``box`` object: :func:`synth.models.meshes.box_with_holes` with the task's holes drilled
  into its top face (bore, depth, 45° chamfer of the given width), as a Coal BVH;
* every ``fixture``: its floor and four walls (seed Figure A.1), one triangle soup;
* every ``pin``: :func:`synth.models.meshes.pin` (tapered tip), as a Coal convex solid (the pin
  is convex: a cone frustum on a cylinder).

Obstacles are named by the objects' AL names (``BOX``, ``RACK``, ``PIN1``) and ``table``. A
hole is a :class:`HoleSite`: its true mouth frame (origin at the centre of the mouth, z the
outward axis, :class:`synth.models.spec.HoleShape`) and its dimensions. Geometry is built once
per task (:class:`WorkcellModel`) and placed per world (:meth:`WorkcellModel.place`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from functools import partial
from typing import Protocol

import coal
import numpy as np
import pinocchio as pin
import trimesh

from synth.exceptions import SpecError
from synth.models.arm.collision import Obstacle, coal_geometry, convex_hull
from synth.models.graph import AttributeGraph
from synth.models.meshes import box_with_holes
from synth.models.meshes import pin as pin_mesh
from synth.models.spec import DEFAULT_FRICTION, HoleShape, PinShape

__all__ = [
    "TABLE",
    "TABLE_MARGIN",
    "TABLE_THICKNESS",
    "HoleSite",
    "NominalPoses",
    "PinModel",
    "Poses",
    "Workcell",
    "WorkcellModel",
]

TABLE = "table"
"""Name of the table slab obstacle."""
TABLE_THICKNESS = 0.05
"""[m] thickness of the table slab below z = 0."""
TABLE_MARGIN = 0.5
"""[m] how far the slab reaches past every task frame and the arm's base."""

_PLACEMENT_TOLERANCE = 1e-6  # [m], [rad]: a hole must sit on its box's top face this exactly


class Poses(Protocol):
    """World poses of the task's frames: a replay trial's true world, or the nominal one."""

    def pose(self, frame: str) -> pin.SE3:
        """World pose of ``frame`` [m]."""
        ...


@dataclass(frozen=True, eq=False)
class NominalPoses:
    """The believed world: every frame at ``graph.world_from`` (what the planner plans in)."""

    graph: AttributeGraph

    def pose(self, frame: str) -> pin.SE3:
        """Nominal world pose of ``frame`` [m] (a copy)."""
        return pin.SE3(self.graph.world_from(frame))


@dataclass(frozen=True, eq=False)
class HoleSite:
    """A hole at its true pose: mouth frame ``world_from_hole`` [m], z out of the hole.

    ``radius`` of the bore, ``depth`` from the mouth to the bottom, ``chamfer`` the radial
    width of the 45° countersink (all [m]); ``owner`` is the obstacle it is drilled into.
    """

    name: str
    frame: str
    owner: str
    world_from_hole: pin.SE3
    radius: float
    depth: float
    chamfer: float

    @property
    def mouth_radius(self) -> float:
        """Radius of the mouth on the surface: bore radius + chamfer width [m]."""
        return self.radius + self.chamfer

    @property
    def axis(self) -> np.ndarray:
        """The hole's outward axis in world coordinates (unit)."""
        return np.asarray(self.world_from_hole.rotation[:, 2], dtype=float).copy()


@dataclass(frozen=True, eq=False)
class PinModel:
    """A pin's solid and profile; frame at the tip centre, z from the tip to the head [m]."""

    name: str
    frame: str
    shape: PinShape
    mesh: trimesh.Trimesh
    geometry: coal.CollisionGeometry

    @property
    def radius(self) -> float:
        """Shaft radius [m]."""
        return self.shape.diameter / 2

    @property
    def tip_radius(self) -> float:
        """Radius of the tip face [m]."""
        return self.shape.tip_radius

    @property
    def length(self) -> float:
        """Length from the tip to the head [m]."""
        return self.shape.length

    def radius_at(self, z: float) -> float:
        """Radius of the section at height ``z`` above the tip [m]; 0 outside the pin."""
        s = self.shape
        if z < 0.0 or z > s.length:
            return 0.0
        if z >= s.tip_taper_length or s.tip_taper_length == 0.0:
            return s.diameter / 2
        return s.tip_radius + (s.diameter / 2 - s.tip_radius) * z / s.tip_taper_length

    def reach(self, placement: pin.SE3) -> float:
        """Max |x| [m] over the pin's points x, placed by ``placement`` (e.g. hand from pin)."""
        points = placement.rotation @ np.asarray(self.mesh.vertices).T
        points += placement.translation[:, None]
        return float(np.max(np.linalg.norm(points, axis=0)))


@dataclass(frozen=True, eq=False)
class Workcell:
    """The static solids of one trial at their true poses, and the holes drilled into them.

    ``obstacles`` excludes the pins, which move (:class:`PinModel`, placed by the machine).
    """

    obstacles: tuple[Obstacle, ...]
    holes: tuple[HoleSite, ...]
    pins: Mapping[str, PinModel]
    friction: float = DEFAULT_FRICTION
    """[1] pin–hole friction coefficient (the task's ``insertion.friction``)."""

    def holes_in(self, owner: str) -> tuple[HoleSite, ...]:
        """The holes drilled into obstacle ``owner``."""
        return tuple(h for h in self.holes if h.owner == owner)

    def hole(self, frame: str) -> HoleSite:
        """The hole whose task frame is ``frame``."""
        for h in self.holes:
            if h.frame == frame:
                return h
        raise KeyError(frame)


def _fixture_mesh(inside: tuple[float, float, float], wall: float, floor: float) -> trimesh.Trimesh:
    """Floor and four walls of an open-topped box (origin at the inside floor centre, z up)."""
    lx, ly, depth = inside
    parts = [
        ((lx + 2 * wall, ly + 2 * wall, floor), (0.0, 0.0, -floor / 2)),
        ((wall, ly + 2 * wall, depth), (lx / 2 + wall / 2, 0.0, depth / 2)),
        ((wall, ly + 2 * wall, depth), (-lx / 2 - wall / 2, 0.0, depth / 2)),
        ((lx, wall, depth), (0.0, ly / 2 + wall / 2, depth / 2)),
        ((lx, wall, depth), (0.0, -ly / 2 - wall / 2, depth / 2)),
    ]
    meshes = []
    for size, centre in parts:
        box = trimesh.creation.box(extents=size)
        box.apply_translation(centre)
        meshes.append(box)
    soup = trimesh.util.concatenate(meshes)
    assert isinstance(soup, trimesh.Trimesh)
    return soup


class WorkcellModel:
    """The task's solids, built once (meshes, Coal geometries) and placed per trial.

    ``extent_points`` [m] are extra world points the table must reach under (the arm's base).
    Raises :class:`~synth.exceptions.SpecError` for a hole the replay cannot drill: one that is
    not in the top face of a box (axis along the box's z, mouth on the face).
    """

    def __init__(self, graph: AttributeGraph, extent_points: Iterable[np.ndarray] = ()) -> None:
        self.graph = graph
        self._index = {f.name: i for i, f in enumerate(graph.spec.frames)}
        self._geometry: dict[object, coal.CollisionGeometry] = {}
        nominal = [graph.world_from(n).translation for n in graph.nodes]
        points = np.array([*nominal, *(np.asarray(p, dtype=float) for p in extent_points)])
        lo, hi = points[:, :2].min(axis=0) - TABLE_MARGIN, points[:, :2].max(axis=0) + TABLE_MARGIN
        size = (float(hi[0] - lo[0]), float(hi[1] - lo[1]), TABLE_THICKNESS)
        centre = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, -TABLE_THICKNESS / 2])
        self.table = Obstacle(TABLE, coal.Box(*size), pin.SE3(np.eye(3), centre))
        self.pins: dict[str, PinModel] = {}
        for name, node in graph.nodes.items():
            if isinstance(node.shape, PinShape):
                s = node.shape
                mesh = pin_mesh(s.length, s.diameter, s.tip_taper_length, s.tip_radius)
                geometry = convex_hull(coal_geometry(mesh))
                self.pins[name] = PinModel(node.al_name, name, s, mesh, geometry)
        names = {node.al_name for node in graph.nodes.values()}
        if TABLE in names:
            raise SpecError("frames", f"the AL name {TABLE!r} is reserved for the table slab")

    # ---- placing

    def place(self, world: Poses) -> Workcell:
        """The static solids and holes at the true poses of ``world``."""
        obstacles: list[Obstacle] = [self.table]
        holes: list[HoleSite] = []
        for name, node in self.graph.nodes.items():
            kind = node.kind
            if kind not in ("box", "fixture"):
                continue
            pose = world.pose(name)
            drilled = self._holes_of(name, world)
            shape = node.shape
            if kind == "box":
                assert shape is not None and shape.type == "box"
                cuts = [h for h, _ in drilled]
                key: tuple[object, ...] = ("box", tuple(shape.size), tuple(cuts))
                geometry = self._cached(key, partial(box_with_holes, shape.size, cuts))
            else:
                assert shape is not None and shape.type == "fixture"
                key = ("fixture", tuple(shape.inside), shape.wall, shape.floor)
                lx, ly, depth = shape.inside
                build = partial(_fixture_mesh, (lx, ly, depth), shape.wall, shape.floor)
                geometry = self._cached(key, build)
            obstacles.append(Obstacle(node.al_name, geometry, pose))
            holes += [site for _, site in drilled]
        insertion = self.graph.spec.insertion
        friction = DEFAULT_FRICTION if insertion is None else insertion.friction
        return Workcell(tuple(obstacles), tuple(holes), self.pins, friction)

    def _cached(self, key: object, build: Callable[[], trimesh.Trimesh]) -> coal.CollisionGeometry:
        geometry = self._geometry.get(key)
        if geometry is None:
            geometry = coal_geometry(build())
            convex_hull(geometry)  # build the hull once; every scene reuses it
            self._geometry[key] = geometry
        return geometry

    def _holes_of(
        self, owner: str, world: Poses
    ) -> list[tuple[tuple[float, float, float, float, float], HoleSite]]:
        """Holes drilled into ``owner``: (x, y, diameter, depth, chamfer) in its frame, site."""
        graph = self.graph
        owner_pose = world.pose(owner)
        out = []
        for node in graph.features("hole"):
            if graph.owner(node.name) != owner:
                continue
            shape = node.shape
            assert isinstance(shape, HoleShape)
            world_pose = world.pose(node.name)
            local = owner_pose.inverse() * world_pose
            owner_shape = graph.nodes[owner].shape
            top = (
                owner_shape.size[2] if owner_shape is not None and owner_shape.type == "box" else 0
            )
            axis = local.rotation[:, 2]
            not_box = owner_shape is None or owner_shape.type != "box"
            mouth_off = abs(local.translation[2] - top) > _PLACEMENT_TOLERANCE
            tilted = axis[2] < 1.0 - _PLACEMENT_TOLERANCE
            if not_box or mouth_off or tilted:
                # name only what is wrong: an axis within the tolerance is along z (its angle
                # in floating point, 1e-6°, is not a second fault)
                faults = []
                if not_box:
                    kind = "no shape" if owner_shape is None else f"a {owner_shape.type}"
                    faults.append(f"its part {graph.nodes[owner].al_name} is {kind}")
                if mouth_off:
                    faults.append(f"its mouth is {100 * float(local.translation[2]):.4g} cm up")
                if tilted:
                    angle = math.degrees(math.acos(min(1.0, float(axis[2]))))
                    faults.append(f"its axis {angle:.3g}° off z")
                wrong = ".pose.rotation" if tilted else "" if not_box else ".pose.translation"
                field = f"frames[{self._index[node.name]}]{wrong}"
                raise SpecError(
                    field,
                    f"hole {node.name!r}: the replay drills holes only into the top face of a box "
                    f"(mouth on the face, {100 * top:.4g} cm up the box's frame; axis along the "
                    f"box's z); {' and '.join(faults)}",
                    graph.spec.line_of(field),
                )
            x, y = (round(float(v), 12) for v in local.translation[:2])
            # the drilled axis is the box's z exactly: keep the hole's spin, drop its tilt
            spin = math.atan2(local.rotation[1, 0], local.rotation[0, 0])
            mouth = owner_pose * pin.SE3(pin.utils.rotate("z", spin), np.array([x, y, top]))
            site = HoleSite(
                node.al_name,
                node.name,
                graph.nodes[owner].al_name,
                mouth,
                shape.diameter / 2,
                shape.depth,
                shape.chamfer_width,
            )
            out.append(((x, y, shape.diameter, shape.depth, shape.chamfer_width), site))
        return out

    def pin_obstacle(self, frame: str, pose: pin.SE3) -> Obstacle:
        """A free pin as an obstacle at world pose ``pose``."""
        model = self.pins[frame]
        return Obstacle(model.name, model.geometry, pose)
