"""Units at the edges: parse ``"3.85 cm"``, ``"0.3 in"``, ``"5 deg"``, ``"8 oz"`` into SI floats.

Everything inside synth is SI (m, rad, s, N, kg). One pint registry serves the whole program.
"""

from __future__ import annotations

import math
import re
import threading
from functools import cache, lru_cache
from typing import Any, Final, Literal

import pint

from synth.exceptions import UnitError

Dimension = Literal["length", "angle", "force", "mass", "time", "torque", "dimensionless"]

# The units synth's own code and tests write numbers in, in SI. The one place they are defined;
# tests/test_units.py checks each against pint's conversion.
MM: Final = 0.001
"""[m] One millimetre."""
CM: Final = 0.01
"""[m] One centimetre, AL's bare length unit."""
INCH: Final = 0.0254
"""[m] One inch (exact by definition)."""
DEG: Final = math.pi / 180.0
"""[rad] One degree."""
OZ: Final = 0.028349523125 * 9.80665
"""[N] One ounce-force: the avoirdupois ounce (exact) under standard gravity, AL's force unit."""

_SI_UNIT: dict[Dimension, str] = {
    "length": "m",
    "angle": "rad",
    "force": "N",
    "mass": "kg",
    "time": "s",
    "torque": "N*m",
    "dimensionless": "",
}


_REGISTRY: list[pint.UnitRegistry] = []
_REGISTRY_LOCK = threading.Lock()


def registry() -> pint.UnitRegistry:
    """The one pint registry; ``oz`` is read as ounce-force when a force is expected.

    Made once under a lock: ``functools.cache`` is no lock, and the service checks specs in
    threads. Two first calls at once (building a registry takes about a second) each made
    their own, and quantities of one met units of the other, "Cannot operate with Unit and
    Unit of different registries", on valid specs, for the life of the server once a cache
    below kept the loser's units (the fourth hunt: 40 of 40 submissions refused).
    """
    if not _REGISTRY:
        with _REGISTRY_LOCK:
            if not _REGISTRY:
                _REGISTRY.append(pint.UnitRegistry(autoconvert_offset_to_baseunit=True))
    return _REGISTRY[0]


def _dimensionality(dim: Dimension) -> pint.util.UnitsContainer:
    ureg = registry()
    if dim == "angle":
        return ureg.radian.dimensionality
    if dim == "dimensionless":
        return ureg.dimensionless.dimensionality
    return ureg.Quantity(1, _SI_UNIT[dim]).dimensionality


_NUMBER = r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
_UNIT_NAME = r"[A-Za-z_][A-Za-z0-9_]*(?:(?:\^|\*\*)[+-]?[0-9])?"
_UNIT = rf"{_UNIT_NAME}(?: *[*/] *{_UNIT_NAME})*"
QUANTITY = re.compile(rf"(?P<number>{_NUMBER})(?: *(?P<unit>{_UNIT}))?", re.ASCII)
"""``<number> [<unit>]``, matched in full after stripping outer white space: a decimal number
(``3.85``, ``-.5``, ``1e-3``) and a unit made of unit names joined by ``*`` or ``/``, each with
an optional one-digit power (``cm``, ``in``, ``rad/s``, ``m/s^2``, ``N*m``, ``cm/deg``). No
parentheses, no operators between numbers, no second number: pint never evaluates an
expression such as ``9**9**9 cm``."""

MAX_MAGNITUDE: dict[Dimension, float] = {
    "length": 1.0e3,
    "angle": 2.0 * math.pi,
    "force": 1.0e6,
    "mass": 1.0e4,
    "time": 1.0e6,
    "torque": 1.0e6,
    "dimensionless": 1.0e6,
}
"""Largest magnitude a task quantity may have once converted to SI: 1 km, one turn (360°),
1 MN, 10 t, ~11.6 days, 1 MN·m, 10⁶. A workcell is metres across, so anything past these is a
typing slip (``1e300 lightyear``), and the limits keep every product the planner forms
(squares of lengths, sums of error chains) far from overflow."""


def read_quantity(text: object) -> Any:
    """``text`` as a pint quantity, if it is ``<number> [<unit>]`` (:data:`QUANTITY`).

    The number must be finite as written (``1e999`` is not). Raises :class:`UnitError` for
    anything else; the caller checks the dimension and the converted value
    (:func:`si_magnitude`).
    """
    if isinstance(text, bool) or not isinstance(text, str | int | float):
        raise UnitError(f"expected a quantity string like '3.85 cm', got {text!r}")
    if isinstance(text, int | float):
        text = repr(float(text)) if isinstance(text, float) else str(text)
    match = QUANTITY.fullmatch(text.strip())
    if match is None:
        raise UnitError(
            f"cannot read {text!r} as a quantity: write a number and a unit, e.g. '3.85 cm', "
            "'2 rad/s' or '8 rad/s^2' (no expressions)"
        )
    number = float(match["number"])
    if not math.isfinite(number):
        raise UnitError(f"{text!r} is not a finite number")
    unit = match["unit"] or "dimensionless"
    try:
        return registry().Quantity(number, unit)
    except Exception as exc:  # pint raises several unrelated types for unknown units
        raise UnitError(f"cannot read {text!r} as a quantity: {exc}") from None


def si_magnitude(q: Any, unit: str, text: object, dim: Dimension | None = None) -> float:
    """The magnitude of ``q`` in ``unit``, checked finite *after* the conversion.

    With ``dim``, also ``|value| ≤`` :data:`MAX_MAGNITUDE` ``[dim]``. ``text`` is the input as
    written, for the message.
    """
    value = float(q.to(unit).magnitude) if unit else float(q.to("dimensionless").magnitude)
    if not math.isfinite(value):
        raise UnitError(f"{text!r} is not finite in SI units ({unit or 'dimensionless'})")
    if dim is not None and abs(value) > MAX_MAGNITUDE[dim]:
        limit = MAX_MAGNITUDE[dim]
        shown = format_quantity(limit, dim, _DISPLAY[dim]) if dim != "dimensionless" else limit
        raise UnitError(f"{text!r} is out of range: a task {dim} is at most {shown} in magnitude")
    return value


RATE_RANGE: tuple[float, float] = (1.0e-3, 1.0e6)
"""[SI] the range of a joint's velocity, acceleration or jerk limit (rad or m per s, s², s³).
Below 1e-3 a joint needs over 50 min for half a turn at that velocity (π / 1e-3 s) and is no
arm a task can plan for; at a jerk of 1e-300 the trajectory generator (Ruckig) fails outright.
Above 1e6 no arm moves, and the limits are that unrealistic only by a slip."""


def rate_si(
    text: object, order: int, kind: Literal["revolute", "prismatic"] | None = None
) -> float:
    """SI value of a joint rate limit: ``order`` 1 velocity, 2 acceleration, 3 jerk.

    A revolute joint's rate is angular (``2 rad/s``, ``90 deg/s``), a prismatic joint's linear
    (``50 cm/s``, ``2 m/s^2``); without ``kind`` either is accepted. The SI value must lie in
    :data:`RATE_RANGE`.
    """
    q = read_quantity(text)
    ureg = registry()
    power = "" if order == 1 else f"^{order}"
    angular = (ureg.second**-order).dimensionality
    linear = (ureg.meter * ureg.second**-order).dimensionality
    allowed = {"revolute": (angular,), "prismatic": (linear,), None: (angular, linear)}[kind]
    if q.dimensionality not in allowed:
        what = {"revolute": f"rad/s{power}", "prismatic": f"m/s{power}"}
        wanted = what[kind] if kind is not None else f"rad/s{power} or m/s{power}"
        raise UnitError(f"{text!r} is not a rate per s{power} ({wanted})")
    unit = ("rad" if q.dimensionality == angular else "m") + f"/s{power}"
    value = si_magnitude(q, unit, text)
    lo, hi = RATE_RANGE
    if not lo <= value <= hi:
        raise UnitError(f"{text!r} must lie between {lo:g} and {hi:g} {unit}")
    return value


def rate_kind(text: object, order: int) -> Literal["revolute", "prismatic"] | None:
    """The joint kind a rate's unit is for: angular (``rad/s``) revolute, linear prismatic.

    None when ``text`` is neither (:func:`rate_si` says why).
    """
    try:
        q = read_quantity(text)
    except UnitError:
        return None
    ureg = registry()
    if q.dimensionality == (ureg.second**-order).dimensionality:
        return "revolute"
    if q.dimensionality == (ureg.meter * ureg.second**-order).dimensionality:
        return "prismatic"
    return None


def parse_quantity(text: object, dim: Dimension) -> float:
    """Parse a quantity with an explicit unit and return its SI value.

    ``dim`` is the expected dimension. A bare number is rejected unless ``dim`` is
    ``"dimensionless"``: every dimensioned number in a task carries its unit. For forces, mass
    units (``8 oz``) are accepted as the weight they exert (standard gravity), the way AL
    programs write force thresholds. The text must be ``<number> <unit>`` (:data:`QUANTITY`),
    and the SI value finite and within :data:`MAX_MAGNITUDE`.
    """
    if isinstance(text, bool) or text is None:
        raise UnitError(f"expected a quantity with a unit of {dim}, got {text!r}")
    if isinstance(text, int | float):
        try:
            value = float(text)
        except OverflowError:  # an int past 1.8e308 (a JSON body's integers are not bounded)
            value = math.inf
        if not math.isfinite(value):  # JSON's 1e999: no unit would make it a quantity
            raise UnitError(f"{text!r} is not a finite number")
        if dim == "dimensionless":
            if abs(value) > MAX_MAGNITUDE[dim]:
                raise UnitError(f"{text!r} is out of range (at most {MAX_MAGNITUDE[dim]:g})")
            return value
        raise UnitError(
            f"{text!r} has no unit; write it with a unit of {dim}, e.g. '{text} {_example(dim)}'"
        )
    if not isinstance(text, str):
        raise UnitError(f"expected a quantity string like '3.85 cm', got {type(text).__name__}")
    return _parse_text(text, dim)


@lru_cache(maxsize=4096)
def _parse_text(text: str, dim: Dimension) -> float:
    """:func:`parse_quantity` of a string, kept for the next call with the same text.

    A task's few quantity strings are read again by every load of the task and of the Stanford
    arm's parameters, at ~80 µs each through pint. The value is a float and a refusal raises
    afresh (``lru_cache`` keeps no exceptions), so a cached call is the uncached one.
    """
    ureg = registry()
    q = read_quantity(text)
    if q.unitless and dim != "dimensionless":
        match = QUANTITY.fullmatch(text.strip())
        if match and match["unit"]:  # '5 rad/rad': units that cancel
            raise UnitError(
                f"{text!r} has no unit: {match['unit']} cancels out; write it with a unit of "
                f"{dim}, e.g. '{match['number']} {_example(dim)}'"
            )
        raise UnitError(
            f"{text!r} has no unit; write it with a unit of {dim}, "
            f"e.g. '{text.strip()} {_example(dim)}'"
        )
    if dim == "force" and q.dimensionality == ureg.kilogram.dimensionality:
        q = q * ureg.standard_gravity
    target = _dimensionality(dim)
    if q.dimensionality != target:
        raise UnitError(_wrong_dimension(text, q, dim))
    if dim != "dimensionless" and ureg.get_root_units(q.units)[1] != _root(dim):
        # pint counts the radian, the bit and the count as dimensionless alike: '2 bit' read as
        # 2 rad, '5 m*rad' as 5 m. The units must reduce to the dimension's own
        raise UnitError(_not_a(text, dim, f"is not a unit of {dim}"))
    return si_magnitude(q, _SI_UNIT[dim], text, dim)


@cache
def _root(dim: Dimension) -> Any:
    """The root units of ``dim``'s SI unit (radian for an angle, gram·metre/second² for a force)."""
    return registry().get_root_units(_SI_UNIT[dim])[1]


def _article(noun: str) -> str:
    return f"an {noun}" if noun[0] in "aeiou" else f"a {noun}"


def _wrong_dimension(text: str, q: Any, dim: Dimension) -> str:
    """``'0.82 deg' is not a length: deg measures an angle; write a length, e.g. '0.82 cm'``.

    The unit's own quantity is named from synth's dimensions; pint counts an angle as
    dimensionless, so a dimensionless unit is named an angle.
    """
    measured = next((d for d in _SI_UNIT if d not in ("dimensionless", dim) and _same(q, d)), None)
    what = f"measures {_article(measured)}" if measured else f"has dimension {q.dimensionality}"
    return _not_a(text, dim, what)


def _not_a(text: str, dim: Dimension, what: str) -> str:
    """``'<text>' is not a <dim>: <unit> <what>; write a <dim>, e.g. '<number> <unit>'``."""
    match = QUANTITY.fullmatch(text.strip())
    number, unit = (match["number"], match["unit"] or "") if match else (text, "")
    return (
        f"{text!r} is not {_article(dim)}: {unit} {what}; write {_article(dim)}, "
        f"e.g. '{number} {_example(dim)}'"
    )


def _same(q: Any, dim: Dimension) -> bool:
    """Whether ``q`` is a quantity of ``dim`` (an angle: any dimensionless unit but none)."""
    if dim == "angle":
        return bool(q.dimensionless) and not q.unitless
    return bool(q.dimensionality == _dimensionality(dim))


_DISPLAY: dict[Dimension, str] = {
    "length": "m",
    "angle": "deg",
    "force": "N",
    "mass": "kg",
    "time": "s",
    "torque": "N*m",
    "dimensionless": "",
}


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
