"""Units at the edges: parse ``"3.85 cm"``, ``"0.3 in"``, ``"5 deg"``, ``"8 oz"`` into SI floats.

Everything inside synth is SI (m, rad, s, N, kg). One pint registry serves the whole program.
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any, Literal

import pint

from synth.exceptions import UnitError

Dimension = Literal["length", "angle", "force", "mass", "time", "torque", "dimensionless"]

_SI_UNIT: dict[Dimension, str] = {
    "length": "m",
    "angle": "rad",
    "force": "N",
    "mass": "kg",
    "time": "s",
    "torque": "N*m",
    "dimensionless": "",
}


@cache
def registry() -> pint.UnitRegistry:
    """The one pint registry; ``oz`` is read as ounce-force when a force is expected."""
    ureg: pint.UnitRegistry = pint.UnitRegistry(autoconvert_offset_to_baseunit=True)
    return ureg


def _dimensionality(dim: Dimension) -> pint.util.UnitsContainer:
    ureg = registry()
    if dim == "angle":
        return ureg.radian.dimensionality
    if dim == "dimensionless":
        return ureg.dimensionless.dimensionality
    return ureg.Quantity(1, _SI_UNIT[dim]).dimensionality


def parse_quantity(text: object, dim: Dimension) -> float:
    """Parse a quantity with an explicit unit and return its SI value.

    ``dim`` is the expected dimension. A bare number is rejected unless ``dim`` is
    ``"dimensionless"``: every dimensioned number in a task carries its unit. For forces, mass
    units (``8 oz``) are accepted as the weight they exert (standard gravity), the way AL
    programs write force thresholds.
    """
    if isinstance(text, bool) or text is None:
        raise UnitError(f"expected a quantity with a unit of {dim}, got {text!r}")
    if isinstance(text, int | float):
        if dim == "dimensionless":
            value = float(text)
            if not math.isfinite(value):
                raise UnitError(f"{text!r} is not a finite number")
            return value
        raise UnitError(
            f"{text!r} has no unit; write it with a unit of {dim}, e.g. '{text} {_example(dim)}'"
        )
    if not isinstance(text, str):
        raise UnitError(f"expected a quantity string like '3.85 cm', got {type(text).__name__}")
    ureg = registry()
    try:
        q: Any = ureg.Quantity(text.strip())
    except Exception as exc:  # pint raises several unrelated types for bad text
        raise UnitError(f"cannot read {text!r} as a quantity: {exc}") from None
    if not isinstance(q, pint.Quantity):
        q = ureg.Quantity(q)
    magnitude = float(q.magnitude)
    if not math.isfinite(magnitude):
        raise UnitError(f"{text!r} is not a finite number")
    if q.unitless and dim != "dimensionless":
        raise UnitError(
            f"{text!r} has no unit; write it with a unit of {dim}, "
            f"e.g. '{text.strip()} {_example(dim)}'"
        )
    if dim == "force" and q.dimensionality == ureg.kilogram.dimensionality:
        q = q * ureg.standard_gravity
    target = _dimensionality(dim)
    if q.dimensionality != target:
        raise UnitError(f"{text!r} is not a {dim} (its dimension is {q.dimensionality})")
    if dim == "dimensionless":
        return float(q.to("dimensionless").magnitude)
    return float(q.to(_SI_UNIT[dim]).magnitude)


def _example(dim: Dimension) -> str:
    return {
        "length": "cm",
        "angle": "deg",
        "force": "N",
        "mass": "kg",
        "time": "s",
        "torque": "N*m",
        "dimensionless": "",
    }[dim]


def format_quantity(value_si: float, dim: Dimension, unit: str, digits: int = 3) -> str:
    """Format an SI value in ``unit`` to ``digits`` significant digits (0.0127 m → '1.27 cm')."""
    ureg = registry()
    base = ureg.Quantity(value_si, _SI_UNIT[dim] or "dimensionless")
    converted = base.to(unit).magnitude
    return f"{converted:.{digits}g} {unit}"
