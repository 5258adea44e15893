"""The manipulator's part of a task spec: the arm model, its rate limits, hand and park frame.

Consumed by :func:`synth.models.arm.load_arm` (the arm) and the planner's hand models.
"""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BeforeValidator, PrivateAttr, field_validator, model_validator

from synth.models.catalog import ARM_MODELS
from synth.models.spec_fields import Pose, PositiveLength, SpecModel, check_al_name
from synth.models.uncertainty import Uncertainty
from synth.units import INCH, rate_kind, rate_si

RATE_FIELDS = ("velocity_limits", "acceleration_limits", "jerk_limits")
"""The arm's rate overrides, by order: velocity, acceleration, jerk."""


def _joint_rates(order: int) -> Any:
    """Per-joint rate limits with units, e.g. ``["2 rad/s", "50 cm/s"]`` → SI floats.

    ``order`` is the power of time: 1 velocity ([rad/s] or [m/s]), 2 acceleration, 3 jerk. A
    revolute joint takes an angular rate, a prismatic joint a linear one; both are stored as SI
    magnitudes in joint order, and :func:`synth.models.arm.load_arm` checks the count.
    """

    def parse(v: Any) -> Any:
        if v is None:
            return None
        if isinstance(v, str) or not isinstance(v, list | tuple):
            raise ValueError("give one rate per joint as a list, e.g. ['2 rad/s', '0.5 m/s']")
        out = []
        for item in v:
            if isinstance(item, bool) or not isinstance(item, str):
                raise ValueError(f"{item!r} has no unit; write e.g. '2 rad/s' or '0.5 m/s'")
            out.append(rate_si(item, order))
        return tuple(out)

    return BeforeValidator(parse)


class ArmSpec(SpecModel):
    """The arm model: a built-in arm (``model: stanford``, ``ur5``, ``panda``, …) or a URDF.

    ``model`` names the seed's Stanford arm or an arm of example-robot-data under its loader's
    name (:data:`synth.models.catalog.ARM_MODELS`; installed by the ``robots`` extra); ``urdf``
    any other arm. ``base`` places the arm's base frame in the world. ``tool_frame`` names the
    URDF frame that AL's hand frame (BHAND/BMANIP) is bound to, and ``tool_offset`` the hand
    frame's pose in it (e.g. from a bare flange such as the UR5's ``tool0`` to the point
    between the finger pads); a built-in arm has defaults for both. ``srdf`` lists link pairs
    whose collisions are disabled (``<disable_collisions>``). ``fingers`` names a URDF's own
    finger joints: they become the hand instead of synth's parametric one.
    ``velocity_limits``, ``acceleration_limits``, ``jerk_limits`` override the model's per-joint
    limits (one entry per joint, with units; SI floats inside).
    """

    model: str | None = None
    urdf: str | None = None
    tool_frame: str | None = None
    package_dirs: tuple[str, ...] = ()
    base: Pose = Pose()
    tool_offset: Pose = Pose()
    srdf: str | None = None
    fingers: tuple[str, ...] = ()
    velocity_limits: Annotated[tuple[float, ...] | None, _joint_rates(1)] = None
    acceleration_limits: Annotated[tuple[float, ...] | None, _joint_rates(2)] = None
    jerk_limits: Annotated[tuple[float, ...] | None, _joint_rates(3)] = None
    _rate_kinds: dict[str, tuple[str | None, ...]] = PrivateAttr(default_factory=dict)
    """Per rate field, the joint kind each entry's unit was written for (angular: revolute,
    linear: prismatic), kept from the task's text for :func:`synth.models.arm.load_arm`."""

    @model_validator(mode="wrap")
    @classmethod
    def _keep_rate_kinds(cls, data: Any, handler: Any) -> Any:
        spec = handler(data)
        if isinstance(data, dict):
            for order, name in enumerate(RATE_FIELDS, start=1):
                raw = data.get(name)
                if isinstance(raw, list | tuple):
                    spec._rate_kinds[name] = tuple(rate_kind(v, order) for v in raw)
        return spec

    def rate_kinds(self, name: str) -> tuple[str | None, ...]:
        """The joint kinds the entries of rate field ``name`` were written for (module text)."""
        return self._rate_kinds.get(name, ())

    @field_validator("model")
    @classmethod
    def _known_model(cls, v: str | None) -> str | None:
        if v is not None and v not in ARM_MODELS:
            raise ValueError(f"unknown arm model {v!r}; built-in arms: {', '.join(ARM_MODELS)}")
        return v

    @model_validator(mode="after")
    def _one_source(self) -> ArmSpec:
        if (self.model is None) == (self.urdf is None):
            raise ValueError(
                "name exactly one arm: 'model: NAME' (e.g. stanford, ur5) or 'urdf: PATH'"
            )
        if self.urdf is not None and not self.tool_frame:
            raise ValueError("a URDF arm needs 'tool_frame', the frame the hand is bound to")
        if self.model is not None:
            extra = [f for f in ("srdf", "package_dirs", "fingers") if f in self.model_fields_set]
            if extra:
                raise ValueError(
                    f"a built-in arm ('model: {self.model}') brings its own files and fingers; "
                    f"remove {', '.join(extra)} or name the URDF with 'urdf:'"
                )
        return self


class HandSpec(SpecModel):
    """Two-finger hand geometry (seed L1984: fingers open through about 4.5 in).

    In the hand frame (origin between the finger pads, z the approach vector) the fingers close
    along x: each is a plate ``finger_thickness`` thick, as wide as a pad, reaching
    ``finger_length`` back to the palm, a box of ``palm_size`` (x, y, z) behind them.
    """

    max_opening: PositiveLength = 4.5 * INCH
    finger_pad_radius: PositiveLength = 0.25 * INCH
    finger_length: PositiveLength = 2.0 * INCH
    finger_thickness: PositiveLength = 0.01
    palm_size: tuple[PositiveLength, PositiveLength, PositiveLength] = (0.14, 0.05, 0.03)


class ParkSpec(SpecModel):
    """The arm's park frame (e.g. ``BPARK``), in world coordinates.

    ``al_name`` is any AL name a frame may take, or ``BPARK`` (:func:`al_name_problem`).
    """

    al_name: str = "BPARK"
    pose: Pose

    @field_validator("al_name")
    @classmethod
    def _al(cls, v: str) -> str:
        return check_al_name(v, role="park")


class ManipulatorSpec(SpecModel):
    """The manipulator: arm model, hand, park frame and hand positioning errors.

    ``al_name`` is any AL name a frame may take, or one of the blue arm's names (``BMANIP``,
    ``BLUE``, ``BARM``, ``BHAND``, ``BFINGERS``), never a constant such as ``TRUE``.
    """

    al_name: str = "BMANIP"
    arm: ArmSpec
    hand: HandSpec = HandSpec()
    park: ParkSpec
    hand_error: Uncertainty | None = None

    @field_validator("al_name")
    @classmethod
    def _al(cls, v: str) -> str:
        return check_al_name(v, role="arm")
