"""Any URDF arm: Pinocchio model and Coal collision meshes from a URDF, placed in the world.

The task's arm section names the URDF, its tool frame (AL's hand frame is ``tool_frame`` ∘
``tool_offset``), optional package directories for ``package://`` mesh URIs and an optional
SRDF whose ``<disable_collisions>`` pairs are never checked. All joints must be revolute or
prismatic (a continuous joint has a 2-number configuration the arm layer does not handle).
Velocity limits come from the URDF unless overridden; URDFs carry no acceleration limits, so
they default to ``velocity / DEFAULT_ACCELERATION_TIME`` unless the task gives them.
"""

from __future__ import annotations

import importlib.metadata
from collections.abc import Sequence
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.exceptions import ArmModelError
from synth.models.arm.arm import Arm
from synth.models.arm.bodies import Body, frame_id
from synth.models.arm.fingers import FingerJoint, urdf_hand
from synth.models.arm.hand import hand_bodies
from synth.models.arm.limits import JointKind, JointLimits
from synth.models.arm.native_stderr import captured_stderr, native_detail
from synth.models.manipulator import HandSpec
from synth.units import RATE_RANGE

DEFAULT_ACCELERATION_TIME: float = 0.25
"""[s] Assumed time to reach full speed when a URDF arm has no acceleration limits (the same
assumption as the Stanford arm's estimated accelerations, fixtures/arms/stanford.yaml)."""

HAND_FRAME = "hand"

_REVOLUTE = {"JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned"}
_PRISMATIC = {"JointModelPX", "JointModelPY", "JointModelPZ", "JointModelPrismaticUnaligned"}


def joint_kinds(model: pin.Model, source: str = "") -> tuple[JointKind, ...]:
    """``revolute`` / ``prismatic`` for joints 1..n; :class:`ArmModelError` for any other type.

    A model without joints (a fixed link tree) cannot move the hand, so it is refused too.
    """
    if model.njoints <= 1:
        raise ArmModelError("the model has no movable joints; an arm needs at least one", source)
    kinds: list[JointKind] = []
    for j in range(1, model.njoints):
        short = model.joints[j].shortname()
        if short in _REVOLUTE:
            kinds.append("revolute")
        elif short in _PRISMATIC:
            kinds.append("prismatic")
        else:
            raise ArmModelError(
                f"joint {model.names[j]!r} is {_URDF_TYPES.get(short.rstrip('XYZ'), short)}; "
                "only revolute and prismatic joints with limits (one coordinate each) are "
                "supported",
                source,
            )
    return tuple(kinds)


_URDF_TYPES = {
    "JointModelRUB": "continuous (a revolute joint without limits): give it type revolute and "
    "its <limit lower upper>",
    "JointModelRevoluteUnboundedUnaligned": "continuous (a revolute joint without limits): give "
    "it type revolute and its <limit lower upper>",
    "JointModelFreeFlyer": "floating",
    "JointModelPlanar": "planar",
}
"""The URDF word for a Pinocchio joint model synth does not drive (its name less the axis)."""


def _mimic_joints(path: Path) -> dict[str, str]:
    """The URDF's joints that follow another (``<mimic joint=…>``): name → the joint followed."""
    try:
        root = ElementTree.parse(path).getroot()
    except ElementTree.ParseError:
        return {}  # Pinocchio read it; urdfdom is the parser of record
    return {
        str(joint.get("name")): str(mimic.get("joint"))
        for joint in root.iter("joint")
        if (mimic := joint.find("mimic")) is not None
    }


def place_base(
    model: pin.Model, geometry: pin.GeometryModel | None, world_from_base: pin.SE3
) -> None:
    """Fold T_world_base into a model built in its base frame (in place).

    Every joint, frame and geometry attached to the universe gets T_world_base·placement, so
    all world-frame quantities (``oMi``, ``oMf``, ``oMg``) come out in the world.
    """
    for j in range(1, model.njoints):
        if model.parents[j] == 0:
            model.jointPlacements[j] = world_from_base * model.jointPlacements[j]
    for frame in model.frames:
        if frame.parentJoint == 0:
            frame.placement = world_from_base * frame.placement
    if geometry is not None:
        for obj in geometry.geometryObjects:
            if obj.parentJoint == 0:
                obj.placement = world_from_base * obj.placement


def disabled_link_pairs(
    model: pin.Model, geometry: pin.GeometryModel, srdf: Path | str
) -> frozenset[frozenset[str]]:
    """Link pairs an SRDF's ``<disable_collisions>`` elements exclude, read by Pinocchio.

    ``pin.removeCollisionPairs`` removes them from every geometry pair of a copy of ``geometry``;
    the removed pairs, by their links, are the result. Pairs of geometry on one joint never
    enter (Pinocchio pairs only bodies of different joints; :class:`CollisionScene` calls them
    adjacent).
    """
    path = Path(srdf)
    if not path.is_file():
        raise ArmModelError("SRDF file not found", str(srdf))
    pairs = geometry.copy()
    pairs.addAllCollisionPairs()
    before = {(p.first, p.second) for p in pairs.collisionPairs}
    try:
        pin.removeCollisionPairs(model, pairs, str(path))
    except (RuntimeError, ValueError) as exc:
        raise ArmModelError(f"cannot read SRDF: {exc}", str(srdf)) from None
    after = {(p.first, p.second) for p in pairs.collisionPairs}

    def link(index: int) -> str:
        return str(model.frames[pairs.geometryObjects[index].parentFrame].name)

    return frozenset(frozenset((link(a), link(b))) for a, b in before - after)


def example_robot_data_dir() -> Path | None:
    """Locate the ``robots`` directory of the optional ``example-robot-data`` package.

    Its URDFs name meshes ``package://example-robot-data/robots/...``, so the package directory
    to pass is this directory's grandparent.
    """
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return None
    for candidate in (
        "cmeel.prefix/share/example-robot-data/robots",
        "share/example-robot-data/robots",
    ):
        path = Path(str(dist.locate_file(candidate)))
        if path.is_dir():
            return path
    return None


def _check_urdf_speeds(
    names: Sequence[str], kinds: Sequence[JointKind], speeds: NDArray[np.float64], source: str
) -> None:
    """The URDF's own speed limits lie in :data:`~synth.units.RATE_RANGE`, as an override must.

    Unchecked, ``velocity="1e9"`` crashed the trajectory timing (exit 70) and ``1e-6`` timed a
    half turn at 36 days; its default acceleration follows it (v / 0.25 s).
    """
    lo, hi = RATE_RANGE
    for name, kind, speed in zip(names, kinds, speeds, strict=True):
        if not lo <= speed <= hi:
            unit = "rad/s" if kind == "revolute" else "m/s"
            raise ArmModelError(
                f"joint {name}'s velocity limit {speed:g} {unit} lies outside {lo:g}–{hi:g} "
                f"{unit}; give the arm's speeds in manipulator.arm.velocity_limits",
                source,
            )


def load_urdf_arm(
    urdf: Path | str,
    tool_frame: str,
    hand: HandSpec,
    *,
    package_dirs: Sequence[str] = (),
    world_from_base: pin.SE3 | None = None,
    tool_offset: pin.SE3 | None = None,
    srdf: Path | str | None = None,
    velocity: Sequence[float] | None = None,
    acceleration: Sequence[float] | None = None,
    jerk: Sequence[float] | None = None,
    fingers: Sequence[str] = (),
) -> Arm:
    """Build an :class:`Arm` from a URDF (see the module docstring for the rules).

    ``fingers`` names the URDF's own finger joints: they are locked closed, and their links'
    shapes become the hand (:mod:`synth.models.arm.fingers`) instead of synth's parametric hand,
    whose ``hand`` spec is then ignored (the caller refuses one given explicitly).
    """
    path = Path(urdf)
    source = str(path)
    if not path.is_file():
        raise ArmModelError("URDF file not found", source)
    try:
        with captured_stderr() as native:
            model = pin.buildModelFromUrdf(str(path))
            geometry = pin.buildGeomFromUrdf(
                model, str(path), pin.GeometryType.COLLISION, package_dirs=list(package_dirs)
            )
    except (RuntimeError, ValueError) as exc:
        detail = native_detail(native.text)
        said = f" (urdfdom: {detail})" if detail else ""
        raise ArmModelError(f"cannot build the model: {exc}{said}", source) from None
    if not model.existFrame(tool_frame):
        known = ", ".join(f.name for f in model.frames if f.type == pin.FrameType.BODY)
        raise ArmModelError(
            f"no frame {tool_frame!r}; body frames: {known}", source, field="tool_frame"
        )
    offset = pin.SE3.Identity() if tool_offset is None else tool_offset
    finger_joints = _finger_joints(model, tool_frame, offset, fingers, source)
    if finger_joints:
        locked = [model.getJointId(f.name) for f in finger_joints]
        model, geometry = pin.buildReducedModel(model, geometry, locked, pin.neutral(model))
    kinds = joint_kinds(model, source)
    followers = _mimic_joints(path)
    for j in range(1, model.njoints):
        if model.names[j] in followers:
            # Pinocchio builds a mimic joint as a free one: a program would drive it alone
            raise ArmModelError(
                f"joint {model.names[j]!r} mimics {followers[model.names[j]]!r}; synth drives "
                "every joint on its own (a mimicking finger joint is named in fingers)",
                source,
            )
    if geometry.ngeoms == 0:
        raise ArmModelError(
            "no link has a <collision> shape: the arm could not be checked against the "
            "workcell or itself",
            source,
        )
    world_from_base = pin.SE3.Identity() if world_from_base is None else world_from_base
    place_base(model, geometry, world_from_base)

    tool = model.frames[frame_id(model, tool_frame)]
    hand_placement = tool.placement * offset
    hand_id = model.addFrame(
        pin.Frame(HAND_FRAME, tool.parentJoint, 0, hand_placement, pin.FrameType.OP_FRAME)
    )
    gripper = (
        urdf_hand(model, geometry, hand_id, tool.name, finger_joints, source)
        if finger_joints
        else None
    )

    n = model.nq
    v = np.asarray(model.velocityLimit if velocity is None else velocity, dtype=float)
    a = (
        v / DEFAULT_ACCELERATION_TIME
        if acceleration is None
        else np.asarray(acceleration, dtype=float)
    )
    for what, values in (("velocity", v), ("acceleration", a), ("jerk", jerk)):
        if values is not None and len(values) != n:
            joints = ", ".join(model.names[j] for j in range(1, model.njoints))
            raise ArmModelError(
                f"{len(values)} values for {n} joints ({joints})", f"manipulator.arm.{what}_limits"
            )
    names = tuple(model.names[j] for j in range(1, model.njoints))
    if velocity is None:
        _check_urdf_speeds(names, kinds, v, source)
    try:
        limits = JointLimits(
            names,
            kinds,
            model.lowerPositionLimit,
            model.upperPositionLimit,
            v,
            a,
            None if jerk is None else np.asarray(jerk, dtype=float),
        )
    except ArmModelError as exc:
        raise ArmModelError(exc.message, source) from None

    replaced = gripper.geometry_names if gripper is not None else frozenset()
    bodies = [
        Body(
            obj.name,
            obj.parentJoint,
            model.frames[obj.parentFrame].name,
            obj.placement.copy(),
            obj.geometry,
            "arm",
        )
        for obj in geometry.geometryObjects
        if obj.name not in replaced
    ]
    if gripper is not None:
        hand = gripper.hand
        bodies += gripper.bodies
    else:
        bodies += hand_bodies(
            hand, int(tool.parentJoint), tool.name, hand_placement, hand.max_opening
        )
    return Arm(
        name=model.name or path.stem,
        model=model,
        hand_frame=hand_id,
        limits=limits,
        hand=hand,
        bodies=tuple(bodies),
        world_from_base=world_from_base,
        disabled_pairs=(
            disabled_link_pairs(model, geometry, srdf) if srdf is not None else frozenset()
        ),
    )


def _finger_joints(
    model: pin.Model, tool_frame: str, tool_offset: pin.SE3, names: Sequence[str], source: str
) -> list[FingerJoint]:
    """The named finger joints: prismatic, with their child link, travel and axis in the hand.

    The axis is measured, not read from the joint type: the finger link's displacement in the
    hand frame per metre of joint travel, from the neutral configuration (finger closed).
    """
    joints: list[FingerJoint] = []
    data = model.createData()
    q0 = pin.neutral(model)

    def finger_in_hand(q: np.ndarray, link: int) -> np.ndarray:
        pin.framesForwardKinematics(model, data, q)
        hand = data.oMf[frame_id(model, tool_frame)] * tool_offset
        return hand.actInv(data.oMf[link]).translation

    for name in names:
        if not model.existJointName(name):
            raise ArmModelError(f"no finger joint {name!r}", source, field="fingers")
        j = model.getJointId(name)
        if model.joints[j].shortname() not in _PRISMATIC:
            raise ArmModelError(f"finger joint {name!r} is not prismatic", source, field="fingers")
        links = [
            k
            for k, f in enumerate(model.frames)
            if f.parentJoint == j and f.type == pin.FrameType.BODY
        ]
        if not links:
            raise ArmModelError(f"finger joint {name!r} carries no link", source, field="fingers")
        step = 1e-3
        q1 = q0.copy()
        q1[model.idx_qs[j]] += step
        axis = (finger_in_hand(q1, links[0]) - finger_in_hand(q0, links[0])) / step
        joints.append(
            FingerJoint(
                name,
                model.frames[links[0]].name,
                float(model.upperPositionLimit[model.idx_qs[j]]),
                axis,
            )
        )
    return joints
