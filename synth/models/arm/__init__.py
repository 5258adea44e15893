"""Arm models on Pinocchio and Coal: the seed's Stanford arm or any URDF arm.

Kinematics (:mod:`.stanford` closed form, :mod:`.ik` damped least squares), motion time
(:mod:`.timing`, ruckig and the seed's rule), collisions (:mod:`.collision` scene,
:mod:`.sweep` swept checks) and solution rating (:mod:`.rating`). :func:`load_arm` builds an
:class:`Arm` from the task's arm and hand sections.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from synth.exceptions import ArmModelError, SpecError
from synth.models.arm.arm import Arm, ClosedFormInverse
from synth.models.arm.bodies import Body
from synth.models.arm.collision import (
    Clearance,
    CollisionScene,
    HeldObject,
    Obstacle,
    coal_geometry,
    grasp_contacts,
)
from synth.models.arm.hand import FINGERS, HAND_BODIES, PALM
from synth.models.arm.ik import IKOptions, IKProblem, IKResult, build_ik, solve_ik, solve_ik_all
from synth.models.arm.limits import QUINTIC_PEAK_TO_AVERAGE, JointLimits
from synth.models.arm.rating import (
    SEED_GRASP_RATING,
    DexterityRating,
    GraspRating,
    JointAngleRating,
    JointMarginRating,
    RatedSolution,
    SeedGraspRating,
    SolutionRating,
    WorstDexterityRating,
    best_solution,
    dexterity,
    grasp_rating,
    nearest_solution,
    rank_solutions,
    solution_rating,
)
from synth.models.arm.robots import load_builtin_arm
from synth.models.arm.stanford import (
    StanfordParameters,
    build_stanford_arm,
    load_stanford_parameters,
    stanford_inverse,
    stanford_inverse_all,
)
from synth.models.arm.sweep import (
    SweepOptions,
    SweepResult,
    swept_path,
    swept_segment,
    swept_trajectory,
)
from synth.models.arm.timing import (
    JIFFY,
    SEED_GRACE,
    JointTrajectory,
    MotionTime,
    TimingOptions,
    motion_time,
    plan_trajectory,
    quintic_motion_time,
    seed_motion_time,
)
from synth.models.arm.urdf import example_robot_data_dir, load_urdf_arm
from synth.models.catalog import BUILTIN_ARMS
from synth.models.graph import pose_to_se3
from synth.models.manipulator import RATE_FIELDS, ArmSpec, HandSpec, ManipulatorSpec
from synth.models.spec import TaskSpec

__all__ = [
    "FINGERS",
    "HAND_BODIES",
    "JIFFY",
    "PALM",
    "QUINTIC_PEAK_TO_AVERAGE",
    "SEED_GRACE",
    "SEED_GRASP_RATING",
    "Arm",
    "Body",
    "Clearance",
    "ClosedFormInverse",
    "CollisionScene",
    "DexterityRating",
    "GraspRating",
    "HeldObject",
    "IKOptions",
    "IKProblem",
    "IKResult",
    "JointAngleRating",
    "JointLimits",
    "JointMarginRating",
    "JointTrajectory",
    "MotionTime",
    "Obstacle",
    "RatedSolution",
    "SeedGraspRating",
    "SolutionRating",
    "StanfordParameters",
    "SweepOptions",
    "SweepResult",
    "TimingOptions",
    "WorstDexterityRating",
    "best_solution",
    "build_ik",
    "build_stanford_arm",
    "check_rates",
    "coal_geometry",
    "dexterity",
    "example_robot_data_dir",
    "grasp_contacts",
    "grasp_rating",
    "load_arm",
    "load_stanford_parameters",
    "load_urdf_arm",
    "manipulator_arm",
    "motion_time",
    "nearest_solution",
    "plan_trajectory",
    "quintic_motion_time",
    "rank_solutions",
    "seed_motion_time",
    "solution_rating",
    "solve_ik",
    "solve_ik_all",
    "stanford_inverse",
    "stanford_inverse_all",
    "swept_path",
    "swept_segment",
    "swept_trajectory",
    "task_arm",
]


def _override(values: tuple[float, ...] | None) -> np.ndarray | None:
    """A rate override as an array (its length checked by :func:`check_rates`)."""
    return None if values is None else np.array(values)


def check_rates(arm_spec: ArmSpec, limits: JointLimits) -> None:
    """Each rate override: one entry per joint, in the unit of its joint's kind.

    A revolute joint's rate is angular (``2 rad/s``), a prismatic joint's linear (``0.5 m/s``);
    ``3 cm/s`` for a revolute joint would be read as 0.03 rad/s.
    """
    n = len(limits.kinds)
    for order, name in enumerate(RATE_FIELDS, start=1):
        values = getattr(arm_spec, name)
        if values is None:
            continue
        if len(values) != n:
            raise ArmModelError(
                f"{len(values)} values for {n} joints ({', '.join(limits.names)})",
                f"manipulator.arm.{name}",
            )
        written = arm_spec.rate_kinds(name)
        for i, (unit_kind, kind) in enumerate(zip(written, limits.kinds, strict=False)):
            if unit_kind is None or unit_kind == kind:
                continue
            power = "" if order == 1 else f"^{order}"
            example = f"2 rad/s{power}" if kind == "revolute" else f"0.5 m/s{power}"
            rate = "an angular" if kind == "revolute" else "a linear"
            raise ArmModelError(
                f"joint {i + 1} ({limits.names[i]}) is {kind}: its rate is {rate} one, e.g. "
                f"'{example}'",
                f"manipulator.arm.{name}[{i}]",
            )


def task_arm(spec: TaskSpec, base_dir: Path | str | None = None) -> Arm:
    """The task's arm (:func:`manipulator_arm`); a fault of its spec at the field's YAML line."""
    assert spec.manipulator is not None
    try:
        return manipulator_arm(spec.manipulator, base_dir)
    except ArmModelError as error:
        if not error.source.startswith("manipulator."):
            raise
        message = error.message.removeprefix(f"{error.source}: ")
        raise SpecError(error.source, message, spec.line_of(error.source)) from None


def manipulator_arm(manipulator: ManipulatorSpec, base_dir: Path | str | None = None) -> Arm:
    """The task's arm with its hand: the ``hand`` section only when the task gives one.

    The planner and the replay build the arm through here, so both see the same hand.
    """
    given = "hand" in manipulator.model_fields_set
    return load_arm(manipulator.arm, manipulator.hand if given else None, base_dir)


def load_arm(
    arm_spec: ArmSpec, hand: HandSpec | None = None, base_dir: Path | str | None = None
) -> Arm:
    """Build the arm a task names: ``model: NAME`` or ``urdf: PATH`` with its tool frame.

    The Stanford arm stands at the spec's ``base`` when given, else at the parameter file's
    ``default_base`` (placed for the seed's workcell). Built-in URDF arms (``ur5``, ``panda``,
    …) come from example-robot-data (:mod:`.robots`). Relative URDF, SRDF and package paths
    are resolved against ``base_dir`` (the task file's directory; default: the working
    directory). Rate-limit overrides must give one value per joint. ``hand`` is synth's
    parametric hand (default :class:`HandSpec`); an arm with its own fingers refuses one.
    """
    hand_spec = hand if hand is not None else HandSpec()
    root = Path(base_dir) if base_dir is not None else Path.cwd()
    base = pose_to_se3(arm_spec.base) if "base" in arm_spec.model_fields_set else None
    offset = pose_to_se3(arm_spec.tool_offset)
    given_offset = offset if "tool_offset" in arm_spec.model_fields_set else None
    fingered = arm_spec.fingers or (
        arm_spec.model in BUILTIN_ARMS and BUILTIN_ARMS[arm_spec.model].fingers
    )
    if fingered and hand is not None:
        raise ArmModelError(
            "this arm has its own fingers, which define the hand's opening and pads; "
            "remove the 'hand' section",
            "manipulator.hand",
        )
    if arm_spec.model in BUILTIN_ARMS:
        try:
            arm = load_builtin_arm(
                arm_spec.model,
                hand_spec,
                world_from_base=base,
                tool_frame=arm_spec.tool_frame,
                tool_offset=given_offset,
                velocity=arm_spec.velocity_limits,
                acceleration=arm_spec.acceleration_limits,
                jerk=arm_spec.jerk_limits,
            )
        except ArmModelError as error:
            if not error.field:
                raise
            # the package's file is not the task's fault: the field the task gave is
            detail = error.message.removeprefix(f"{error.source}: ")
            if error.field == "tool_offset":
                detail += f" (it replaces the built-in {arm_spec.model}'s own hand offset)"
            raise ArmModelError(detail, f"manipulator.arm.{error.field}") from None
        check_rates(arm_spec, arm.limits)
        return arm
    if arm_spec.model == "stanford":
        arm = build_stanford_arm(hand_spec, base, tool_offset=offset)
        check_rates(arm_spec, arm.limits)
        rates = {
            "velocity": _override(arm_spec.velocity_limits),
            "acceleration": _override(arm_spec.acceleration_limits),
            "jerk": _override(arm_spec.jerk_limits),
        }
        if all(v is None for v in rates.values()):
            return arm
        return dataclasses.replace(arm, limits=arm.limits.replace(**rates))
    assert arm_spec.urdf is not None and arm_spec.tool_frame is not None  # ArmSpec validates
    urdf = root / arm_spec.urdf
    try:
        arm = load_urdf_arm(
            urdf,
            arm_spec.tool_frame,
            hand_spec,
            package_dirs=[str(root / d) for d in arm_spec.package_dirs],
            world_from_base=base,
            tool_offset=offset,
            srdf=None if arm_spec.srdf is None else root / arm_spec.srdf,
            velocity=arm_spec.velocity_limits,
            acceleration=arm_spec.acceleration_limits,
            jerk=arm_spec.jerk_limits,
            fingers=arm_spec.fingers,
        )
    except ArmModelError as error:
        if error.source != str(urdf):
            raise
        # the file's own fault is the field that names it (a task's line, not only a path)
        field = error.field or "urdf"
        raise ArmModelError(error.message, f"manipulator.arm.{field}") from None
    check_rates(arm_spec, arm.limits)
    return arm
