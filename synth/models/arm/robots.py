"""Built-in URDF arms: ``model: ur5``, ``model: panda``, … from example-robot-data.

The names and files are :data:`synth.models.catalog.BUILTIN_ARMS`; they resolve inside the
installed package (:func:`synth.models.arm.urdf.example_robot_data_dir`), so a task file that
names one is portable. Unless the task overrides them, the tool frame, SRDF and finger joints
are the catalog's, and the hand frame is placed by the hand:

* a robot with its own fingers (the Panda): the catalog's point between the pads;
* a bare flange (the URs): synth's parametric hand bolted to it, the hand frame
  ``L_f + h_palm`` ahead of the flange along its z (the palm's rear face on the flange).

UR arms get ``ur_analytic_ik``'s closed form (:mod:`.ur`) when it is installed and agrees
with the URDF's forward kinematics; other arms keep the multi-start DLS solver (:mod:`.ik`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from synth.exceptions import ArmModelError
from synth.models.arm.arm import Arm
from synth.models.arm.bodies import frame_id
from synth.models.arm.hand import palm_top
from synth.models.arm.ur import ur_inverse
from synth.models.arm.urdf import example_robot_data_dir, load_urdf_arm
from synth.models.catalog import BUILTIN_ARMS, ROBOTS_EXTRA
from synth.models.manipulator import HandSpec

FIELD = "manipulator.arm.model"


def builtin_hand_offset(name: str, hand: HandSpec) -> pin.SE3:
    """T_tool_hand for a built-in arm (module docstring)."""
    entry = BUILTIN_ARMS[name]
    if entry.hand_from_tool is not None:
        translation, about_z = entry.hand_from_tool
        return pin.SE3(pin.utils.rotate("z", about_z), np.array(translation, dtype=float))
    return pin.SE3(np.eye(3), np.array([0.0, 0.0, palm_top(hand)]))


def load_builtin_arm(
    name: str,
    hand: HandSpec,
    *,
    world_from_base: pin.SE3 | None = None,
    tool_frame: str | None = None,
    tool_offset: pin.SE3 | None = None,
    velocity: Sequence[float] | None = None,
    acceleration: Sequence[float] | None = None,
    jerk: Sequence[float] | None = None,
) -> Arm:
    """Build a catalog arm; :class:`ArmModelError` naming the extra when it is not installed."""
    entry = BUILTIN_ARMS.get(name)
    if entry is None:
        known = ", ".join(sorted(BUILTIN_ARMS))
        raise ArmModelError(f"unknown arm {name!r}; built-in URDF arms: {known}", FIELD)
    robots = example_robot_data_dir()
    if robots is None:
        raise ArmModelError(
            f"arm {name!r} comes from the example-robot-data package, which is not installed: "
            f"{ROBOTS_EXTRA}",
            FIELD,
        )
    root = robots / entry.directory
    arm = load_urdf_arm(
        root / entry.urdf,
        tool_frame or entry.tool_frame,
        hand,
        package_dirs=[str(robots.parent.parent)],
        world_from_base=world_from_base,
        tool_offset=tool_offset if tool_offset is not None else builtin_hand_offset(name, hand),
        srdf=None if entry.srdf is None else root / entry.srdf,
        velocity=velocity,
        acceleration=acceleration,
        jerk=jerk,
        fingers=entry.fingers,
    )
    arm = dataclasses.replace(arm, name=name)
    if entry.closed_form is not None:
        closed = ur_inverse(
            entry.closed_form,
            arm.model,
            frame_id(arm.model, entry.tool_frame),
            arm.hand_frame,
            arm.limits,
        )
        if closed is not None:
            arm = dataclasses.replace(arm, closed_form=closed)
    return arm
