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
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pinocchio as pin

from synth.exceptions import ArmModelError
from synth.models.arm.arm import Arm
from synth.models.arm.bodies import Body
from synth.models.arm.hand import hand_bodies
from synth.models.arm.limits import JointKind, JointLimits
from synth.models.spec import HandSpec

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
                f"joint {model.names[j]!r} is {short}; only revolute and prismatic joints "
                f"(one coordinate each) are supported",
                source,
            )
    return tuple(kinds)


def place_base(
    model: pin.Model, geometry: pin.GeometryModel | None, transform_world_base: pin.SE3
) -> None:
    """Fold T_world_base into a model built in its base frame (in place).

    Every joint, frame and geometry attached to the universe gets T_world_base·placement, so
    all world-frame quantities (``oMi``, ``oMf``, ``oMg``) come out in the world.
    """
    for j in range(1, model.njoints):
        if model.parents[j] == 0:
            model.jointPlacements[j] = transform_world_base * model.jointPlacements[j]
    for frame in model.frames:
        if frame.parentJoint == 0:
            frame.placement = transform_world_base * frame.placement
    if geometry is not None:
        for obj in geometry.geometryObjects:
            if obj.parentJoint == 0:
                obj.placement = transform_world_base * obj.placement


def disabled_link_pairs(srdf: Path | str) -> frozenset[frozenset[str]]:
    """Link pairs of an SRDF's ``<disable_collisions link1=… link2=…/>`` elements."""
    try:
        root = ET.parse(srdf).getroot()
    except (OSError, ET.ParseError) as exc:
        raise ArmModelError(f"cannot read SRDF: {exc}", str(srdf)) from None
    return frozenset(
        frozenset((e.attrib["link1"], e.attrib["link2"]))
        for e in root.iter("disable_collisions")
        if "link1" in e.attrib and "link2" in e.attrib
    )


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


def load_urdf_arm(
    urdf: Path | str,
    tool_frame: str,
    hand: HandSpec,
    *,
    package_dirs: Sequence[str] = (),
    transform_world_base: pin.SE3 | None = None,
    tool_offset: pin.SE3 | None = None,
    srdf: Path | str | None = None,
    velocity: Sequence[float] | None = None,
    acceleration: Sequence[float] | None = None,
    jerk: Sequence[float] | None = None,
) -> Arm:
    """Build an :class:`Arm` from a URDF (see the module docstring for the rules)."""
    path = Path(urdf)
    source = str(path)
    if not path.is_file():
        raise ArmModelError("URDF file not found", source)
    try:
        model = pin.buildModelFromUrdf(str(path))
        geometry = pin.buildGeomFromUrdf(
            model, str(path), pin.GeometryType.COLLISION, package_dirs=list(package_dirs)
        )
    except (RuntimeError, ValueError) as exc:
        raise ArmModelError(f"cannot build the model: {exc}", source) from None
    kinds = joint_kinds(model, source)
    if not model.existFrame(tool_frame):
        known = ", ".join(f.name for f in model.frames if f.type == pin.FrameType.BODY)
        raise ArmModelError(f"no frame {tool_frame!r}; body frames: {known}", source)
    t_wb = pin.SE3.Identity() if transform_world_base is None else transform_world_base
    place_base(model, geometry, t_wb)

    tool = model.frames[model.getFrameId(tool_frame)]
    hand_placement = tool.placement * (pin.SE3.Identity() if tool_offset is None else tool_offset)
    hand_id = model.addFrame(
        pin.Frame(HAND_FRAME, tool.parentJoint, 0, hand_placement, pin.FrameType.OP_FRAME)
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
            raise ArmModelError(f"{len(values)} {what} limits for {n} joints", source)
    names = tuple(model.names[j] for j in range(1, model.njoints))
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
    ]
    hand_link = model.frames[model.getFrameId(tool_frame)].name
    bodies += hand_bodies(hand, int(tool.parentJoint), hand_link, hand_placement, hand.max_opening)
    return Arm(
        name=model.name or path.stem,
        model=model,
        hand_frame=hand_id,
        limits=limits,
        hand=hand,
        bodies=tuple(bodies),
        transform_world_base=t_wb,
        disabled_pairs=disabled_link_pairs(srdf) if srdf is not None else frozenset(),
    )
