"""A URDF's own two-finger gripper as synth's hand: palm and finger bodies, and the hand's numbers.

When a robot has its own fingers (the Franka hand), synth's parametric hand (:mod:`.hand`) is
not added; the finger joints are locked closed (q = 0) in the kinematic model, and the finger
links' collision shapes become the bodies ``finger_left`` / ``finger_right``, the tool link's the
``palm``, each merged into one mesh in AL's hand frame (origin between the pads, z the approach,
fingers closing along x). The collision scene opens them along x like the parametric fingers.

The :class:`~synth.models.manipulator.HandSpec` the planner and the replay reason with is read off
those shapes, in the hand frame, with the finger joints at 0:

* ``max_opening`` = gap₀ + Σ upper limits of the finger joints (both slide outwards; gap₀ is the
  distance between the pads' inner faces when closed, clamped at 0);
* the *pad* of a finger is its collision shape whose inner face is nearest x = 0 (Franka: the
  rubber tip); ``finger_pad_radius`` = min(half its extent along y, half along z), the largest
  square pad inside it, and ``finger_thickness`` its extent along x;
* ``finger_length`` = how far the palm's front face lies behind the hand origin, −max z of the
  palm; ``palm_size`` = the palm's bounding-box extents.

The hand frame must sit at the pads' centre (within 1 mm) with the finger joints sliding along
±x; otherwise :class:`~synth.exceptions.ArmModelError` names the tool offset to fix.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin
import trimesh
from numpy.typing import NDArray

from synth.exceptions import ArmModelError
from synth.models.arm.bodies import Body
from synth.models.arm.hand import FINGERS, PALM
from synth.models.manipulator import HandSpec

_CENTRE_TOLERANCE = 1e-3  # [m] hand origin to the pads' centre
_AXIS_TOLERANCE = 1e-3  # [1] finger travel off the hand's x


@dataclass(frozen=True)
class FingerJoint:
    """A finger joint of the full model: its child link, travel and world-frame motion axis."""

    name: str
    link: str
    upper: float
    axis_in_hand: NDArray[np.float64]


def _mesh(geometry: coal.CollisionGeometry) -> trimesh.Trimesh:
    """A triangle mesh of a Coal shape in its own frame [m]."""
    if isinstance(geometry, coal.Box):
        return trimesh.creation.box(extents=2 * np.asarray(geometry.halfSide))
    if isinstance(geometry, coal.Cylinder):
        return trimesh.creation.cylinder(geometry.radius, 2 * geometry.halfLength)
    if isinstance(geometry, coal.Capsule):
        return trimesh.creation.capsule(2 * geometry.halfLength, geometry.radius)
    if isinstance(geometry, coal.Sphere):
        return trimesh.creation.icosphere(radius=geometry.radius)
    if isinstance(geometry, coal.BVHModelBase):
        vertices = np.asarray(geometry.vertices(), dtype=float)
        faces = np.array(
            [[geometry.tri_indices(i)[k] for k in range(3)] for i in range(geometry.num_tris)]
        )
        return trimesh.Trimesh(vertices, faces, process=False)
    raise ArmModelError(f"a finger or palm shape of type {type(geometry).__name__}")


def _bvh(mesh: trimesh.Trimesh) -> coal.BVHModelOBBRSS:
    bvh = coal.BVHModelOBBRSS()
    bvh.beginModel(len(mesh.faces), len(mesh.vertices))
    bvh.addVertices(np.asarray(mesh.vertices, dtype=np.float64))
    bvh.addTriangles(np.asarray(mesh.faces, dtype=np.int64))
    bvh.endModel()
    return bvh


def _joined(meshes: list[trimesh.Trimesh]) -> trimesh.Trimesh:
    """One mesh of several (a triangle soup: the shapes may overlap)."""
    joined = trimesh.util.concatenate(meshes)
    assert isinstance(joined, trimesh.Trimesh)
    return joined


def _metres(value: float) -> str:
    """A length for the task schema, which takes quantities with units ([m], exactly)."""
    return f"{float(value)!r} m"


def _in_hand(obj: pin.GeometryObject, hand_from_joint: pin.SE3) -> trimesh.Trimesh:
    mesh = _mesh(obj.geometry)
    mesh.apply_transform((hand_from_joint * obj.placement).homogeneous)
    return mesh


@dataclass(frozen=True)
class URDFHand:
    """The gripper read from a URDF: the hand's numbers and its bodies at full opening."""

    hand: HandSpec
    bodies: tuple[Body, ...]
    geometry_names: frozenset[str]
    """The URDF geometry objects these bodies replace."""


def urdf_hand(
    model: pin.Model,
    geometry: pin.GeometryModel,
    hand_frame: int,
    tool_link: str,
    fingers: Sequence[FingerJoint],
    source: str,
) -> URDFHand:
    """Read the gripper (module docstring); ``model`` has the finger joints locked at 0."""
    frame = model.frames[hand_frame]
    joint = int(frame.parentJoint)
    joint_from_hand = frame.placement
    hand_from_joint = joint_from_hand.inverse()
    if len(fingers) != 2:
        raise ArmModelError(
            f"{len(fingers)} finger joints; a two-finger gripper has 2",
            source,
            field="fingers",
        )
    sides: dict[str, tuple[trimesh.Trimesh, trimesh.Trimesh, FingerJoint]] = {}
    used: set[str] = set()
    for finger in fingers:
        axis = finger.axis_in_hand
        if abs(abs(float(axis[0])) - 1.0) > _AXIS_TOLERANCE:
            raise ArmModelError(
                f"finger joint {finger.name!r} slides along {np.round(axis, 3).tolist()} in the "
                "hand frame, not along x: turn the hand frame (tool_offset) about z",
                source,
                field="tool_offset",
            )
        objects = [
            o for o in geometry.geometryObjects if model.frames[o.parentFrame].name == finger.link
        ]
        if not objects:
            raise ArmModelError(
                f"finger link {finger.link!r} has no collision shapes", source, field="fingers"
            )
        used |= {o.name for o in objects}
        shapes = [_in_hand(o, hand_from_joint) for o in objects]
        inner = [float(np.min(np.abs(s.vertices[:, 0]))) for s in shapes]
        pad = shapes[int(np.argmin(inner))]
        name = FINGERS[0] if float(np.mean(pad.vertices[:, 0])) < 0 else FINGERS[1]
        if name in sides:
            raise ArmModelError(
                "both fingers lie on the same side of the hand's x = 0", source, field="fingers"
            )
        if float(axis[0]) * (1 if name == FINGERS[1] else -1) < 0:
            raise ArmModelError(
                f"finger joint {finger.name!r} closes as it rises", source, field="fingers"
            )
        sides[name] = (_joined(shapes), pad, finger)
    _, left_pad, left_joint = sides[FINGERS[0]]
    _, right_pad, right_joint = sides[FINGERS[1]]
    gap0 = max(0.0, float(np.min(right_pad.vertices[:, 0]) - np.max(left_pad.vertices[:, 0])))
    max_opening = gap0 + left_joint.upper + right_joint.upper
    pad_centre = np.concatenate([left_pad.vertices, right_pad.vertices]).mean(axis=0)
    lo, hi = right_pad.bounds
    centre = np.array([0.0, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2])
    if np.linalg.norm(centre) > _CENTRE_TOLERANCE or abs(pad_centre[0]) > _CENTRE_TOLERANCE:
        raise ArmModelError(
            f"the hand frame is {1000 * np.linalg.norm(centre):.1f} mm from the finger pads' "
            f"centre (pad centre in the hand frame: {np.round(1000 * centre, 2).tolist()} mm); "
            "set tool_offset to the point between the pads",
            source,
            field="tool_offset",
        )
    palm_objects = [
        o for o in geometry.geometryObjects if model.frames[o.parentFrame].name == tool_link
    ]
    if not palm_objects:
        raise ArmModelError(
            f"the tool link {tool_link!r} has no collision shapes (palm)",
            source,
            field="tool_frame",
        )
    used |= {o.name for o in palm_objects}
    palm = _joined([_in_hand(o, hand_from_joint) for o in palm_objects])
    palm_lo, palm_hi = palm.bounds
    finger_length = -float(palm_hi[2])
    if finger_length <= 0:
        raise ArmModelError(
            "the palm reaches past the hand origin between the pads", source, field="tool_offset"
        )
    extent = hi - lo
    hand = HandSpec.model_validate(
        {
            "max_opening": _metres(max_opening),
            "finger_pad_radius": _metres(min(extent[1], extent[2]) / 2),
            "finger_length": _metres(finger_length),
            "finger_thickness": _metres(extent[0]),
            "palm_size": [_metres(v) for v in palm_hi - palm_lo],
        }
    )
    bodies = [Body(PALM, joint, tool_link, joint_from_hand, _bvh(palm), "hand")]
    for name, (mesh, _, finger) in sides.items():
        side = -1.0 if name == FINGERS[0] else 1.0
        opened = pin.SE3(np.eye(3), np.array([side * finger.upper, 0.0, 0.0]))
        bodies.append(Body(name, joint, finger.link, joint_from_hand * opened, _bvh(mesh), "hand"))
    return URDFHand(hand, tuple(bodies), frozenset(used))
