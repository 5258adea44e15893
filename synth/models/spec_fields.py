"""The field types every record of a task spec is built from: quantities, AL names, poses.

Every dimensioned number carries its unit (``"3.85 cm"``, ``"5 deg"``), parsed by
:mod:`synth.units`; a validated record holds SI floats (m, rad, N). Records are frozen and
refuse unknown keys (:class:`SpecModel`).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, model_validator

from synth.al.names import NameRole, al_name_problem
from synth.units import parse_quantity


def _length(v: Any) -> float:
    return parse_quantity(v, "length")


def _angle(v: Any) -> float:
    return parse_quantity(v, "angle")


def _force(v: Any) -> float:
    return parse_quantity(v, "force")


Length = Annotated[float, BeforeValidator(_length)]
"""A length given with its unit, stored in [m]."""
Angle = Annotated[float, BeforeValidator(_angle)]
"""An angle given with its unit, stored in [rad]."""
Force = Annotated[float, BeforeValidator(_force)]
"""A force (or a weight such as ``8 oz``), stored in [N]."""
NonNegativeAngle = Annotated[float, BeforeValidator(_angle), Field(ge=0)]
PositiveLength = Annotated[float, BeforeValidator(_length), Field(gt=0)]
NonNegativeLength = Annotated[float, BeforeValidator(_length), Field(ge=0)]


class SpecModel(BaseModel):
    """A record of the task spec: frozen, and unknown keys are refused."""

    model_config = ConfigDict(extra="forbid", frozen=True)


def check_al_name(value: str, *, role: NameRole = "frame") -> str:
    """``value`` upper-cased if it may name a ``role`` in AL (:func:`al_name_problem`)."""
    problem = al_name_problem(value, role=role)
    if problem:
        raise ValueError(problem)
    return value.upper()


class Rotation(SpecModel):
    """One elementary rotation ``rot(axis, angle)``; a pose composes a list left to right."""

    axis: Literal["x", "y", "z"]
    angle: Angle

    @model_validator(mode="before")
    @classmethod
    def _from_short_form(cls, data: Any) -> Any:
        # {z: "90 deg"} is the short form of {axis: z, angle: "90 deg"}.
        if isinstance(data, dict) and len(data) == 1:
            ((key, value),) = data.items()
            if key in ("x", "y", "z"):
                return {"axis": key, "angle": value}
            if key not in ("axis", "angle"):
                raise ValueError(
                    f"{key!r} is not an axis: a rotation is {{x|y|z: angle}} or "
                    "{axis: x|y|z, angle: …}"
                )
        if isinstance(data, dict) and len(data) > 1:
            axes = [key for key in data if key in ("x", "y", "z")]
            if axes:
                # {z: 30 deg, x: 10 deg} was refused as "z: unknown field", a valid key
                raise ValueError(
                    f"one axis per rotation, not {', '.join(map(repr, data))}: write "
                    f"[{', '.join(f'{{{k}: …}}' for k in axes)}], composed left to right"
                )
        return data


class Pose(SpecModel):
    """Nominal pose of a frame in its parent: ``trans(rot_1 ∘ rot_2 ∘ …, translation)``."""

    translation: tuple[Length, Length, Length] = (0.0, 0.0, 0.0)
    rotation: tuple[Rotation, ...] = ()
