"""Collision bodies: a Coal geometry rigidly attached to a joint of the kinematic model.

A :class:`Body` is what becomes one Pinocchio ``GeometryObject``: a name, the joint that carries
it (0 = the fixed world/base), the frame it belongs to (a link name, used by SRDF pair rules),
its pose in the joint frame and a Coal shape. The helpers build the primitives the Stanford arm
and the generic hand are made of; sizes are full lengths in [m].
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Literal

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import NDArray
from scipy.spatial import ConvexHull, QhullError

Role = Literal["arm", "hand", "held", "environment"]


@dataclass(frozen=True, eq=False)
class Body:
    """A collision shape carried by a joint.

    ``placement`` is T_joint_body (pose of the shape's own frame in the joint frame); ``link``
    names the link (or environment object) the body belongs to; ``role`` groups bodies for
    pair rules (arm links, the hand, a held object, the environment).
    """

    name: str
    joint: int
    link: str
    placement: pin.SE3
    geometry: coal.CollisionGeometry
    role: Role = "arm"

    def geometry_object(self, model: pin.Model) -> pin.GeometryObject:
        """Make the Pinocchio geometry object (parent frame looked up by link name)."""
        frame = frame_id(model, self.link) if model.existFrame(self.link) else 0
        frame = frame if frame < len(model.frames) else 0
        return pin.GeometryObject(self.name, self.joint, frame, self.placement, self.geometry)


def frame_id(model: pin.Model, name: str) -> int:
    """The frame called ``name``: its link's (BODY) frame when a joint has the name too.

    URDF links and joints have separate names, so a link and the fixed joint above it may share
    one (example-robot-data's Unitree Z1: ``gripperStator``); Pinocchio's ``getFrameId`` of the
    name alone then raises "several frames match". A fixed joint's frame and its child link's
    coincide, so the link's frame is the one meant either way.
    """
    if model.existFrame(name, pin.FrameType.BODY):
        return int(model.getFrameId(name, pin.FrameType.BODY))
    return int(model.getFrameId(name))


_AXIS_ROTATION: dict[str, np.ndarray] = {
    "z": np.eye(3),
    # Coal cylinders and capsules lie along their local z; rotate z onto x or y.
    "x": pin.utils.rotate("y", np.pi / 2),
    "y": pin.utils.rotate("x", -np.pi / 2),
}


def cylinder_along(
    radius: float, start: float, end: float, axis: Literal["x", "y", "z"] = "z"
) -> tuple[coal.Cylinder, pin.SE3]:
    """Make a cylinder of ``radius`` [m] spanning ``start ≤ s ≤ end`` [m] along a frame axis.

    Returns the Coal shape and its placement in that frame (Coal cylinders are centred on
    their origin along local z).
    """
    if end <= start:
        raise ValueError(f"cylinder end {end} must exceed start {start}")
    direction = {"x": np.array([1.0, 0, 0]), "y": np.array([0, 1.0, 0]), "z": np.array([0, 0, 1.0])}
    centre = direction[axis] * (start + end) / 2
    return coal.Cylinder(radius, end - start), pin.SE3(_AXIS_ROTATION[axis], centre)


def box_at(
    size: tuple[float, float, float], centre: tuple[float, float, float]
) -> tuple[coal.Box, pin.SE3]:
    """Make an axis-aligned box of full side lengths ``size`` [m] centred at ``centre`` [m]."""
    return coal.Box(*size), pin.SE3(np.eye(3), np.array(centre, dtype=float))


def z_range(geometry: coal.CollisionGeometry, world_from_shape: pin.SE3) -> tuple[float, float]:
    """Lowest and highest world z [m] of a placed shape's local axis-aligned bounding box.

    z is linear over the box, so its extremes are r·c ± |r|·h with r the rotation's third row,
    c and h the box's centre and half-extents (plus the placement's own z).
    """
    geometry.computeLocalAABB()
    box = geometry.aabb_local
    lo, hi = np.asarray(box.min_), np.asarray(box.max_)
    row = world_from_shape.rotation[2]
    centre = float(row @ (lo + hi) / 2 + world_from_shape.translation[2])
    reach = float(np.abs(row) @ (hi - lo) / 2)
    return centre - reach, centre + reach


def bounding_radius(geometry: coal.CollisionGeometry, placement: pin.SE3) -> float:
    """Radius [m] of a ball about the joint-frame origin that contains the placed shape.

    r = |t + R·c| + ρ, with (c, ρ) the centre and radius of the ball around the shape's local
    axis-aligned bounding box (Coal's ``aabb_center``, ``aabb_radius``).
    """
    geometry.computeLocalAABB()
    centre = placement.translation + placement.rotation @ np.asarray(geometry.aabb_center)
    return float(np.linalg.norm(centre) + geometry.aabb_radius)


def hull_points(geometry: coal.CollisionGeometry, placement: pin.SE3) -> NDArray[np.float64] | None:
    """The vertices (N, 3) [m] of the placed shape's convex hull, or None for a curved shape.

    A box, a mesh and a convex polytope lie inside the hull of their vertices, so a convex
    function of the point (a lever, a support) is largest over the shape at one of these. A
    sphere, cylinder or capsule has no finite set of vertices whose hull holds it: None.
    """
    if isinstance(geometry, coal.Box):
        half = np.asarray(geometry.halfSide, dtype=float)
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
        local = signs * half
    elif isinstance(geometry, coal.BVHModelBase):
        local = np.asarray(geometry.vertices(), dtype=float).reshape(-1, 3)
    elif isinstance(geometry, coal.ConvexBase):
        local = np.asarray(geometry.points(), dtype=float).reshape(-1, 3)
    else:
        return None
    if len(local) == 0:
        return None
    placed = local @ placement.rotation.T + placement.translation
    # A flat or degenerate set has no 3-D hull: all its vertices are still a valid set
    with contextlib.suppress(QhullError):
        placed = placed[ConvexHull(placed).vertices]
    return placed
