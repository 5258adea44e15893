"""Which arm configuration reaches a hand pose next, and why none does.

Every hand target of a motion goes through the arm's inverse kinematics (closed form for the
Stanford arm, seed eqs. 14–32; damped least squares otherwise). Of the attainable solutions the
one nearest the arm's current configuration (max-norm) is taken, so a motion keeps the arm's
branch (no wrist flip) whenever the branch reaches.

When no attainable solution exists the pose is classified:

* ``unreachable`` — the pose is outside the arm's workspace. For the Stanford arm: no
  algebraic solution at all, or none whose boom extension S3 lies within its travel (the
  wrist centre is out of reach). For other arms every failure is reported this way.
* ``joint_limit`` — the wrist centre is within reach but every solution needs a revolute joint
  beyond its limits (e.g. θ5 ∉ [−110°, 110°], seed L963, for a hand turned back towards the arm).
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.models.arm.arm import Arm
from synth.models.arm.rating import nearest_solution
from synth.models.arm.stanford import StanfordInverse, stanford_inverse_all

__all__ = [
    "BRANCH_JUMP",
    "ReachProblem",
    "branch_jump",
    "describe_pose",
    "leaving_branch",
    "solve_continuing",
    "solve_near",
]

_TOLERANCE = 1e-9


class ReachProblem(Exception):
    """No attainable configuration: ``kind`` and a one-line ``detail``."""

    def __init__(self, kind: Literal["unreachable", "joint_limit"], detail: str) -> None:
        super().__init__(f"{kind}: {detail}")
        self.kind: Literal["unreachable", "joint_limit"] = kind
        self.detail = detail


def describe_pose(pose: pin.SE3) -> str:
    """``(x, y, z) cm, approach (ax, ay, az)``: a hand pose for messages."""
    x, y, z = (_centimetres(float(v)) for v in pose.translation)
    a = pose.rotation[:, 2]
    return f"({x}, {y}, {z}) cm, approach ({a[0]:.2f}, {a[1]:.2f}, {a[2]:.2f})"


def _centimetres(metres: float) -> str:
    """``12.34``; past a kilometre, ``1.225e+169`` (a hundred and seventy digits say nothing)."""
    cm = 100.0 * metres
    return f"{cm:.2f}" if abs(cm) < 1e5 else f"{cm:.4g}"


FAR = 1e3
"""[m] No arm reaches a hand pose this far from its base: refused before the inverse
kinematics, whose squares overflow to NaN near 1e154 m (an AL literal of 1e180 cm crashed the
replay, the fourth hunt)."""


def solve_near(arm: Arm, pose: pin.SE3, near: NDArray[np.float64]) -> NDArray[np.float64]:
    """The attainable configuration reaching ``pose`` nearest ``near``; ReachProblem if none."""
    offset = pose.translation - arm.world_from_base.translation
    if not (np.all(np.isfinite(pose.homogeneous)) and float(np.max(np.abs(offset))) < FAR):
        raise ReachProblem(
            "unreachable", f"the hand pose {describe_pose(pose)} is out of the arm's reach"
        )
    q = nearest_solution(arm, arm.inverse(pose, hint=near), near)
    if q is not None:
        return q
    raise _problem(arm, pose)


BRANCH_JUMP = 0.5 * np.pi
"""[rad] A revolute joint turning more than this to reach a pose a few millimetres away has left
the arm's branch (a wrist flip turns two joints by π): no small motion gets there."""


def branch_jump(arm: Arm, q: NDArray[np.float64], near: NDArray[np.float64]) -> str | None:
    """The revolute joints ``q`` turns more than :data:`BRANCH_JUMP` from ``near``, in words."""
    turned = [
        f"{arm.limits.names[i]} by {np.degrees(abs(float(q[i] - near[i]))):.0f}°"
        for i, kind in enumerate(arm.limits.kinds)
        if kind == "revolute" and abs(float(q[i] - near[i])) > BRANCH_JUMP
    ]
    return ", ".join(turned) or None


def leaving_branch(motion: str, turned: str) -> ReachProblem:
    """The ``joint_limit`` problem of a small motion that only another branch makes."""
    return ReachProblem(
        "joint_limit",
        f"{motion} needs a joint past its stop on the arm's branch; the nearest other solution "
        f"turns {turned} at once",
    )


def solve_continuing(
    arm: Arm, pose: pin.SE3, near: NDArray[np.float64], motion: str
) -> NDArray[np.float64]:
    """:func:`solve_near` for a small motion the arm makes without a planned path.

    A centring move of a few millimetres is not swept joint by joint: the arm is set to the
    solution it ends in. When the branch it stands on cannot reach (a joint at its stop), the
    nearest attainable solution is another branch, and setting it would turn the wrist by
    180° in no time. That is a ``joint_limit`` :class:`ReachProblem` naming ``motion``.
    """
    q = solve_near(arm, pose, near)
    turned = branch_jump(arm, q, near)
    if turned is not None:
        raise leaving_branch(motion, turned)
    return q


def _degrees(angle_rad: float) -> str:
    """An excess in degrees, to 0.1° or, below it, to two figures (never a bare 0.0°)."""
    degrees = float(np.degrees(angle_rad))
    return f"{degrees:.1f}°" if degrees >= 0.095 else f"{degrees:.2g}°"


def _problem(arm: Arm, pose: pin.SE3) -> ReachProblem:
    where = describe_pose(pose)
    inverse = arm.closed_form
    if not isinstance(inverse, StanfordInverse):
        return ReachProblem("unreachable", f"no arm solution reaches the hand pose {where}")
    t = inverse.world_from_base.inverse() * pose * inverse.tool_offset.inverse()
    candidates = stanford_inverse_all(inverse.params, t.rotation, t.translation)
    limits = arm.limits
    prismatic = [i for i, kind in enumerate(limits.kinds) if kind == "prismatic"]
    within = [
        np.array(c)
        for c in candidates
        if all(
            limits.lower[i] - _TOLERANCE <= c[i] <= limits.upper[i] + _TOLERANCE for i in prismatic
        )
    ]
    if not within:
        return ReachProblem("unreachable", f"the hand pose {where} is out of the arm's reach")

    # the candidate closest to its limits names the joints it would need beyond them
    def excess(q: NDArray[np.float64]) -> NDArray[np.float64]:
        wrapped = np.array(q, dtype=float)
        for i, kind in enumerate(limits.kinds):
            if kind == "revolute":
                centre = 0.5 * (limits.lower[i] + limits.upper[i])
                wrapped[i] = centre + (wrapped[i] - centre + np.pi) % (2 * np.pi) - np.pi
        return np.maximum(limits.lower - wrapped, 0.0) + np.maximum(wrapped - limits.upper, 0.0)

    best = min(within, key=lambda q: float(np.sum(excess(q))))
    over = excess(best)
    joints = ", ".join(
        f"{limits.names[i]} {_degrees(over[i])} past its limit"
        for i in np.flatnonzero(over > _TOLERANCE)
    )
    return ReachProblem(
        "joint_limit", f"the hand pose {where} needs {joints or 'a joint beyond its limits'}"
    )
