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

from synth.exceptions import ArmModelError
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
    JointAngleRating,
    JointMarginRating,
    RatedSolution,
    SolutionRating,
    best_solution,
    nearest_solution,
    rank_solutions,
)
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
    seed_motion_time,
)
from synth.models.arm.urdf import example_robot_data_dir, load_urdf_arm
from synth.models.graph import pose_to_se3
from synth.models.spec import ArmSpec, HandSpec

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
    "SolutionRating",
    "StanfordParameters",
    "SweepOptions",
    "SweepResult",
    "TimingOptions",
    "best_solution",
    "build_ik",
    "build_stanford_arm",
    "coal_geometry",
    "example_robot_data_dir",
    "grasp_contacts",
    "load_arm",
    "load_stanford_parameters",
    "load_urdf_arm",
    "motion_time",
    "nearest_solution",
    "plan_trajectory",
    "rank_solutions",
    "seed_motion_time",
    "solve_ik",
    "solve_ik_all",
    "stanford_inverse",
    "stanford_inverse_all",
    "swept_path",
    "swept_segment",
    "swept_trajectory",
]


def _override(values: tuple[float, ...] | None, n: int, field: str) -> np.ndarray | None:
    if values is None:
        return None
    if len(values) != n:
        raise ArmModelError(f"{len(values)} values for {n} joints", f"manipulator.arm.{field}")
    return np.array(values)


def load_arm(
    arm_spec: ArmSpec, hand: HandSpec | None = None, base_dir: Path | str | None = None
) -> Arm:
    """Build the arm a task names: ``model: stanford`` or ``urdf: PATH`` with its tool frame.

    The Stanford arm stands at the spec's ``base`` when given, else at the parameter file's
    ``default_base`` (placed for the seed's workcell). Relative URDF, SRDF and package paths
    are resolved against ``base_dir`` (the task file's directory; default: the working
    directory). Rate-limit overrides must give one value per joint.
    """
    hand_spec = hand if hand is not None else HandSpec()
    root = Path(base_dir) if base_dir is not None else Path.cwd()
    base = pose_to_se3(arm_spec.base) if "base" in arm_spec.model_fields_set else None
    offset = pose_to_se3(arm_spec.tool_offset)
    if arm_spec.model == "stanford":
        arm = build_stanford_arm(hand_spec, base, tool_offset=offset)
        n = arm.nq
        rates = {
            "velocity": _override(arm_spec.velocity_limits, n, "velocity_limits"),
            "acceleration": _override(arm_spec.acceleration_limits, n, "acceleration_limits"),
            "jerk": _override(arm_spec.jerk_limits, n, "jerk_limits"),
        }
        if all(v is None for v in rates.values()):
            return arm
        return dataclasses.replace(arm, limits=arm.limits.replace(**rates))
    assert arm_spec.urdf is not None and arm_spec.tool_frame is not None  # ArmSpec validates
    return load_urdf_arm(
        root / arm_spec.urdf,
        arm_spec.tool_frame,
        hand_spec,
        package_dirs=[str(root / d) for d in arm_spec.package_dirs],
        transform_world_base=base,
        tool_offset=offset,
        srdf=None if arm_spec.srdf is None else root / arm_spec.srdf,
        velocity=arm_spec.velocity_limits,
        acceleration=arm_spec.acceleration_limits,
        jerk=arm_spec.jerk_limits,
    )
