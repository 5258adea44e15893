"""The arms a task can name with ``manipulator.arm.model``.

The seed's Stanford arm and the arms of the optional ``example-robot-data`` package, under the
names its loaders use.

Pure data, so the task schema can validate a name without loading any model
(:func:`synth.models.arm.robots.load_builtin_arm` builds them). A built-in entry gives the URDF
and SRDF inside the package, the tool frame AL's hand frame hangs from, the closed-form inverse
to use, the URDF's own finger joints when the robot has a gripper, and where the hand frame sits
in the tool frame when it has one (between the pads, fingers closing along x).

The UR entries share ``ur5.srdf``: example-robot-data ships an SRDF only for the UR5, and the
UR3 and UR10 have the same links under the same names (the pairs it disables are the UR5's
touching neighbours, base–upper arm and forearm–wrists).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

STANFORD = "stanford"
"""The seed's Scheinman arm (chapter III), built in with its closed form."""

ROBOTS_EXTRA = "pip install 'synth[robots]'  (from a checkout: pip install -e '.[robots]')"
"""How to install the optional package the built-in URDF arms come from."""


@dataclass(frozen=True)
class BuiltinArm:
    """One example-robot-data arm: files inside its ``robots`` directory and synth's defaults."""

    directory: str
    """Subdirectory of example-robot-data's ``robots`` directory (``ur_description``)."""
    urdf: str
    """URDF path inside ``directory``."""
    srdf: str | None
    """SRDF path inside ``directory`` (its ``<disable_collisions>`` pairs), if any."""
    tool_frame: str
    """URDF frame AL's hand frame is bound to."""
    closed_form: str | None = None
    """Name of the closed-form inverse (``ur_analytic_ik``'s module: ``ur5``), None: DLS."""
    fingers: tuple[str, ...] = ()
    """The URDF's own finger joints (prismatic, closing along the hand's x); () = no gripper,
    synth's parametric hand is mounted on the tool frame."""
    hand_from_tool: tuple[tuple[float, float, float], float] | None = None
    """For a robot with fingers: the hand frame in the tool frame as (translation [m], rotation
    about the tool's z [rad]); None: the parametric hand's own offset along z."""


_UR = "ur_description"
_UR_SRDF = "srdf/ur5.srdf"

BUILTIN_ARMS: dict[str, BuiltinArm] = {
    "ur3": BuiltinArm(_UR, "urdf/ur3_robot.urdf", _UR_SRDF, "tool0", "ur3"),
    "ur3_limited": BuiltinArm(_UR, "urdf/ur3_joint_limited_robot.urdf", _UR_SRDF, "tool0", "ur3"),
    "ur5": BuiltinArm(_UR, "urdf/ur5_robot.urdf", _UR_SRDF, "tool0", "ur5"),
    "ur5_limited": BuiltinArm(
        _UR,
        "urdf/ur5_joint_limited_robot.urdf",
        "srdf/ur5_joint_limited_robot.srdf",
        "tool0",
        "ur5",
    ),
    "ur10": BuiltinArm(_UR, "urdf/ur10_robot.urdf", _UR_SRDF, "tool0", "ur10"),
    "ur10_limited": BuiltinArm(
        _UR, "urdf/ur10_joint_limited_robot.urdf", _UR_SRDF, "tool0", "ur10"
    ),
    # The Franka hand's pads (the "rubber tip" boxes of panda.urdf) are centred 58.4 + 45.25 mm
    # down panda_hand's z; its fingers slide along panda_hand's y, so AL's hand frame (fingers
    # closing along x) is panda_hand turned 90° about z.
    "panda": BuiltinArm(
        "panda_description",
        "urdf/panda.urdf",
        "srdf/panda.srdf",
        "panda_hand",
        None,
        ("panda_finger_joint1", "panda_finger_joint2"),
        ((0.0, 0.0, 0.0584 + 0.04525), math.pi / 2),
    ),
}

ARM_MODELS: tuple[str, ...] = (STANFORD, *BUILTIN_ARMS)
"""Every name ``manipulator.arm.model`` accepts."""
