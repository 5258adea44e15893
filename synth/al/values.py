"""AL values, their dimensions, and AL's operator table.

AL has typed geometric values (seed L1150–1160; al-language.md §2): scalars, vectors,
rotations, frames and transes, plus booleans, strings and events. Here:

- :class:`Scalar` — a float with a :class:`Exponents`;
- :class:`Vector` — three floats with one :class:`Exponents` (a direction such as ``ZHAT`` is
  dimensionless, a position or displacement is a length);
- :class:`Rotation` — a 3×3 rotation matrix;
- :class:`Pose` — a Pinocchio ``pin.SE3`` tagged ``"frame"`` (a location in the world) or
  ``"trans"`` (a relation between frames); AL stores both the same way (EAL83, a 3×4 array);
- ``bool`` and ``str`` — booleans and strings;
- :class:`Event` — a counting event for ``SIGNAL`` / ``WAIT``.

**Units and dimensions.** Values are SI inside, as everywhere in synth: lengths [m], angles
[rad], forces [N], times [s], torques [N·m]. AL's units are scalar constants you multiply by
(seed-al-subset.md §1): ``CM`` = 0.01 m, ``INCHES`` = 0.0254 m, ``DEG`` = π/180 rad,
``RAD`` = 1 rad, ``OZ`` = 0.278 N (ounce-force), ``SEC`` = 1 s (:data:`UNITS`). A dimension is a
vector of integer exponents over the four base quantities (length, angle, force, time), so
``10*OZ*INCHES`` is a torque (force·length) and ``(.572/R)*RAD`` an angle.

A bare number is *dimensionless*. It stays a pure number under ``*`` and ``/``
(``2*INCHES`` is 2 inches). Where a dimensioned value is required (``+``, ``-`` and relations
against a dimensioned operand, a vector component next to dimensioned ones, the vector of
``TRANS(rot, v)``, the angle of ``ROT``, an ``OPEN`` width), a dimensionless value is read in
AL's bare units — **cm, rad, oz, s** (seed-al-subset.md §1: "bare numbers in generated code
are cm, radians, seconds"; oz by analogy) — so ``VECTOR(0,0,3.54)`` inside ``TRANS`` is
3.54 cm and ``ABS(DISTANCE_OFF) > .169`` compares with 0.169 cm. For a composite dimension the
bare unit is the product (torque: oz·cm). Any other mismatch (``length + angle``) is an
error: generated programs must be dimensionally consistent, and the referee should say so
rather than warn.

**Operator table** (``s`` scalar, ``v`` vector, ``r`` rot, ``f`` frame, ``t`` trans, ``b``
boolean). Precedence is the parser's (``*`` ``/`` > ``.`` > ``+`` ``-`` > relations > NOT >
AND > OR; al.lark).

==========================  ========  ==========================================================
operands                    result    meaning
==========================  ========  ==========================================================
``s * s``, ``s / s``        s         product, quotient; dimensions multiply / divide
``s * v``, ``v * s``,       v         scale a vector (dimensions multiply)
``v / s``
``r * r``                   r         composition (apply the right one first)
``r * v``                   v         rotate a vector (its dimension is kept)
``f * t``                   f         the location ``t`` relative to ``f`` (S:1157, S:2723)
``t * t``                   t         composition of relations
``t * f``                   t         ``INV(A)*B`` is B relative to A, a relation (S:1416)
``f * v``, ``t * v``        v         map a point: R·v + p; v must be a length (S:1416)
``s + s``, ``s - s``        s         dimensions must agree (bare numbers adapt, see above)
``v + v``, ``v - v``        v         as for scalars
``f ± v``, ``v + f``        f         translate by a world vector, rotation kept (S:1411)
``t ± v``, ``v + t``        t         as for frames
``f ± r``, ``t ± r``        f, t      ``F + R`` = ``F*TRANS(R, 0)``: turn about F's own origin
                                      and axes (``pin+rot(xhat,10*deg)``, S:1390; §7 decision)
``v . v``                   s         dot product; dimensions multiply (S:1416, S:2737)
``-s``, ``-v``, ``+x``      s, v      negation, identity
``s rel s``                 b         ``< > = ≤ ≥ ≠``; dimensions must agree
``b = b``, ``b ≠ b``        b         boolean equality
``b AND b``, ``b OR b``     b         conjunction, disjunction
``NOT b``                   b         negation
``|s|``, ``|v|``, ``|r|``   s         absolute value, Euclidean norm, rotation angle [rad]
==========================  ========  ==========================================================

Everything else — ``FRAME + SCALAR``, ``f * f``, ``r * f``, ``v * v``, ``s + v`` — raises
:class:`OperandError`, which the interpreter turns into an
:class:`~synth.exceptions.ALRuntimeError` at the operator's AL line.

**Builtins and predeclared names** live in :mod:`synth.al.builtins`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal, TypeAlias

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from synth.units import CM, OZ

__all__ = [
    "ANGLE",
    "BARE_UNITS",
    "DIMENSIONLESS",
    "FORCE",
    "LENGTH",
    "TIME",
    "TORQUE",
    "Event",
    "Exponents",
    "OperandError",
    "Pose",
    "PoseKind",
    "Rotation",
    "Scalar",
    "Value",
    "Vector",
    "binary",
    "coerce",
    "coerce_vector",
    "compare",
    "describe",
    "length_of",
    "magnitude",
    "scalar_pair",
    "type_name",
    "typed",
    "unary",
]


class OperandError(TypeError):
    """An operator or builtin got operands of the wrong type or dimension.

    Internal to :mod:`synth.al`: the interpreter converts it into
    :class:`~synth.exceptions.ALRuntimeError` with the AL line and column.
    """


# --------------------------------------------------------------------------------------------
# Dimensions


@dataclass(frozen=True)
class Exponents:
    """An AL physical dimension: integer exponents over length, angle, force and time.

    (The task spec's :data:`synth.units.Dimension` is the *name* of a kind of quantity.)
    """

    length: int = 0
    angle: int = 0
    force: int = 0
    time: int = 0

    def _exponents(self) -> tuple[int, int, int, int]:
        return (self.length, self.angle, self.force, self.time)

    def __mul__(self, other: Exponents) -> Exponents:
        a, b = self._exponents(), other._exponents()
        return Exponents(*(x + y for x, y in zip(a, b, strict=True)))

    def __truediv__(self, other: Exponents) -> Exponents:
        a, b = self._exponents(), other._exponents()
        return Exponents(*(x - y for x, y in zip(a, b, strict=True)))

    def sqrt(self) -> Exponents:
        """The dimension whose square is this one; :class:`OperandError` if there is none."""
        exponents = self._exponents()
        if any(e % 2 for e in exponents):
            raise OperandError(f"SQRT of a {self.name} has no dimension")
        return Exponents(*(e // 2 for e in exponents))

    @property
    def dimensionless(self) -> bool:
        """True for a pure number."""
        return self == DIMENSIONLESS

    @property
    def bare_factor(self) -> float:
        """SI value of one bare AL unit of this dimension: cm^L · rad^A · oz^F · s^T."""
        return float(CM**self.length * OZ**self.force)

    @property
    def name(self) -> str:
        """Its name (``length``, ``torque``, ...), or a product such as ``length^2·time^-1``."""
        known = _DIMENSION_NAMES.get(self._exponents())
        if known is not None:
            return known
        parts = []
        for base, e in zip(("length", "angle", "force", "time"), self._exponents(), strict=True):
            if e:
                parts.append(base if e == 1 else f"{base}^{e}")
        return "·".join(parts)


DIMENSIONLESS = Exponents()
LENGTH = Exponents(length=1)
ANGLE = Exponents(angle=1)
FORCE = Exponents(force=1)
TIME = Exponents(time=1)
TORQUE = Exponents(length=1, force=1)

_DIMENSION_NAMES: dict[tuple[int, int, int, int], str] = {
    (0, 0, 0, 0): "dimensionless",
    (1, 0, 0, 0): "length",
    (0, 1, 0, 0): "angle",
    (0, 0, 1, 0): "force",
    (0, 0, 0, 1): "time",
    (1, 0, 1, 0): "torque",
}

BARE_UNITS: dict[str, str] = {"length": "cm", "angle": "rad", "force": "oz", "time": "s"}
"""AL's bare unit per base quantity (seed-al-subset.md §1)."""


# --------------------------------------------------------------------------------------------
# Values


@dataclass(frozen=True)
class Scalar:
    """A dimensioned scalar; ``value`` is SI ([m], [rad], [N], [s], [N·m], ...)."""

    value: float
    dim: Exponents = DIMENSIONLESS

    def __post_init__(self) -> None:
        if type(self.value) is not float:
            object.__setattr__(self, "value", float(self.value))


def _frozen_array(values: ArrayLike, shape: tuple[int, ...]) -> NDArray[np.float64]:
    array = np.array(values, dtype=float)
    if array.shape != shape:
        raise ValueError(f"expected shape {shape}, got {array.shape}")
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False)
class Vector:
    """A 3-vector with one dimension for all components; ``value`` SI, read-only."""

    value: NDArray[np.float64]
    dim: Exponents = DIMENSIONLESS

    def __post_init__(self) -> None:
        object.__setattr__(self, "value", _frozen_array(self.value, (3,)))


@dataclass(frozen=True, eq=False)
class Rotation:
    """A rotation; ``matrix`` is a read-only 3×3 rotation matrix (world from rotated)."""

    matrix: NDArray[np.float64]

    def __post_init__(self) -> None:
        object.__setattr__(self, "matrix", _frozen_array(self.matrix, (3, 3)))


PoseKind = Literal["frame", "trans"]


@dataclass(frozen=True, eq=False)
class Pose:
    """A frame (a location) or a trans (a relation): a Pinocchio ``SE3``, translation [m].

    ``se3`` is a private copy; never mutate it (use ``pin.SE3(pose.se3)`` to get one to edit).
    """

    se3: pin.SE3
    kind: PoseKind = "frame"

    def __post_init__(self) -> None:
        object.__setattr__(self, "se3", pin.SE3(self.se3))


@dataclass(eq=False)
class Event:
    """An AL event: ``SIGNAL`` adds one to ``count``; ``WAIT`` takes one, or blocks while 0."""

    name: str
    count: int = field(default=0)


Value: TypeAlias = Scalar | Vector | Rotation | Pose | bool | str | Event


def type_name(value: Value) -> str:
    """AL's name for the type of ``value`` (``scalar``, ``vector``, ``rot``, ``frame``, ...)."""
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, Scalar):
        return "scalar"
    if isinstance(value, Vector):
        return "vector"
    if isinstance(value, Rotation):
        return "rot"
    if isinstance(value, Pose):
        return value.kind
    if isinstance(value, str):
        return "string"
    if isinstance(value, Event):
        return "event"
    raise TypeError(f"not an AL value: {value!r}")


def typed(value: Value) -> str:
    """``a frame``, ``a length scalar``: the operand as named in error messages."""
    name = type_name(value)
    if isinstance(value, Scalar | Vector) and not value.dim.dimensionless:
        name = f"{value.dim.name} {name}"
    article = "an" if name[0] in "aeiou" else "a"
    return f"{article} {name}"


def describe(value: Value) -> str:
    """Text of a value for messages: scalars and vectors in AL's bare units (``1.71 cm``)."""
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    if isinstance(value, str):
        return value
    if isinstance(value, Scalar):
        return _with_unit(value.value / value.dim.bare_factor, value.dim)
    if isinstance(value, Vector):
        parts = ", ".join(f"{x:.6g}" for x in value.value / value.dim.bare_factor)
        return _with_unit(None, value.dim, f"({parts})")
    if isinstance(value, Rotation):
        axis_angle = pin.log3(value.matrix)
        angle = float(np.linalg.norm(axis_angle))
        if angle < 1e-12:
            return "NILROTN"
        axis = ", ".join(f"{x:.4g}" for x in axis_angle / angle)
        return f"ROT(({axis}), {math.degrees(angle):.6g} deg)"
    if isinstance(value, Pose):
        rot = describe(Rotation(value.se3.rotation))
        where = ", ".join(f"{x / CM:.6g}" for x in value.se3.translation)
        return f"{value.kind.upper()}({rot}, ({where}) cm)"
    return f"EVENT {value.name}"


def _with_unit(number: float | None, dim: Exponents, text: str | None = None) -> str:
    shown = f"{number:.6g}" if text is None else text
    if dim.dimensionless:
        return shown
    units = []
    for base, e in zip(("length", "angle", "force", "time"), dim._exponents(), strict=True):
        if e:
            unit = BARE_UNITS[base]
            units.append(unit if e == 1 else f"{unit}^{e}")
    return f"{shown} {'·'.join(units)}"


# --------------------------------------------------------------------------------------------
# Exponents checks


def coerce(value: Scalar, dim: Exponents, what: str = "value") -> Scalar:
    """``value`` as a scalar of ``dim``: a bare number is read in AL's bare units (cm, rad, ...).

    Raises:
        OperandError: ``value`` has another, non-empty dimension.
    """
    if value.dim == dim:
        return value
    if value.dim.dimensionless:
        return Scalar(value.value * dim.bare_factor, dim)
    raise OperandError(f"{what} must be a {dim.name}, not a {value.dim.name}")


def coerce_vector(value: Vector, dim: Exponents, what: str = "vector") -> Vector:
    """:func:`coerce` for vectors."""
    if value.dim == dim:
        return value
    if value.dim.dimensionless:
        return Vector(value.value * dim.bare_factor, dim)
    raise OperandError(f"{what} must be a {dim.name} vector, not a {value.dim.name} vector")


def _common(a: Exponents, b: Exponents, op: str) -> Exponents:
    """The dimension two operands of ``+ - rel`` share (a bare operand adapts to the other)."""
    if a == b or b.dimensionless:
        return a
    if a.dimensionless:
        return b
    raise OperandError(f"cannot apply '{op}' to a {a.name} and a {b.name}")


def scalar_pair(a: Scalar, b: Scalar, op: str) -> tuple[float, float, Exponents]:
    """Both scalars' values [SI] in their common dimension (bare numbers adapt), and it."""
    dim = _common(a.dim, b.dim, op)
    return coerce(a, dim).value, coerce(b, dim).value, dim


def _vector_pair(
    a: Vector, b: Vector, op: str
) -> tuple[NDArray[np.float64], NDArray[np.float64], Exponents]:
    dim = _common(a.dim, b.dim, op)
    return coerce_vector(a, dim).value, coerce_vector(b, dim).value, dim


def length_of(v: Vector, what: str) -> NDArray[np.float64]:
    """The vector as a length [m] (a bare vector is read in cm); ``what`` names it in errors."""
    return coerce_vector(v, LENGTH, what).value


# --------------------------------------------------------------------------------------------
# Operators


def _translate(pose: Pose, vector: Vector, sign: float) -> Pose:
    moved = pin.SE3(pose.se3)
    moved.translation = pose.se3.translation + sign * length_of(vector, "a frame's offset")
    return Pose(moved, pose.kind)


def _turn(pose: Pose, rot: Rotation, sign: float) -> Pose:
    matrix = rot.matrix if sign > 0 else rot.matrix.T
    return Pose(pose.se3 * pin.SE3(matrix, np.zeros(3)), pose.kind)


def _mul(a: Value, b: Value) -> Value:
    if isinstance(a, Scalar) and isinstance(b, Scalar):
        return Scalar(a.value * b.value, a.dim * b.dim)
    if isinstance(a, Scalar) and isinstance(b, Vector):
        return Vector(a.value * b.value, a.dim * b.dim)
    if isinstance(a, Vector) and isinstance(b, Scalar):
        return Vector(a.value * b.value, a.dim * b.dim)
    if isinstance(a, Rotation) and isinstance(b, Rotation):
        return Rotation(a.matrix @ b.matrix)
    if isinstance(a, Rotation) and isinstance(b, Vector):
        return Vector(a.matrix @ b.value, b.dim)
    if isinstance(a, Pose) and isinstance(b, Vector):
        return Vector(a.se3.act(length_of(b, "a point mapped by a frame")), LENGTH)
    if isinstance(a, Pose) and isinstance(b, Pose):
        if a.kind == "frame" and b.kind == "frame":
            raise OperandError(
                "frame * frame is not defined (the relation of B to A is INV(A)*B; "
                "a location relative to A is A*TRANS(...))"
            )
        kind: PoseKind = "frame" if (a.kind, b.kind) == ("frame", "trans") else "trans"
        return Pose(a.se3 * b.se3, kind)
    raise OperandError(f"cannot multiply {typed(a)} by {typed(b)}")


def _div(a: Value, b: Value) -> Value:
    if isinstance(b, Scalar):
        if b.value == 0.0:
            raise OperandError("division by zero")
        if isinstance(a, Scalar):
            return Scalar(a.value / b.value, a.dim / b.dim)
        if isinstance(a, Vector):
            return Vector(a.value / b.value, a.dim / b.dim)
    raise OperandError(f"cannot divide {typed(a)} by {typed(b)}")


def _add(a: Value, b: Value, sign: float) -> Value:
    op = "+" if sign > 0 else "-"
    if isinstance(a, Scalar) and isinstance(b, Scalar):
        x, y, dim = scalar_pair(a, b, op)
        return Scalar(x + sign * y, dim)
    if isinstance(a, Vector) and isinstance(b, Vector):
        u, w, dim = _vector_pair(a, b, op)
        return Vector(u + sign * w, dim)
    if isinstance(a, Pose) and isinstance(b, Vector):
        return _translate(a, b, sign)
    if sign > 0 and isinstance(a, Vector) and isinstance(b, Pose):
        return _translate(b, a, 1.0)
    if isinstance(a, Pose) and isinstance(b, Rotation):
        return _turn(a, b, sign)
    verb, joint = ("add", "to") if sign > 0 else ("subtract", "from")
    raise OperandError(f"cannot {verb} {typed(b)} {joint} {typed(a)}")


def _dot(a: Value, b: Value) -> Value:
    if isinstance(a, Vector) and isinstance(b, Vector):
        return Scalar(float(a.value @ b.value), a.dim * b.dim)
    raise OperandError(
        f"the dot product needs two vectors, not {typed(a)} and {typed(b)}"
        + (" (use DISPL(frame) for a frame's position)" if isinstance(b, Pose) else "")
    )


def _logic(a: Value, b: Value, op: str) -> Value:
    if isinstance(a, bool) and isinstance(b, bool):
        return (a and b) if op == "AND" else (a or b)
    raise OperandError(f"{op} needs two booleans, not {typed(a)} and {typed(b)}")


def binary(op: str, left: Value, right: Value) -> Value:
    """Apply AL's binary operator ``op`` (``+ - * / . AND OR``) per the module's type table."""
    if op == "*":
        return _mul(left, right)
    if op == "/":
        return _div(left, right)
    if op == "+":
        return _add(left, right, 1.0)
    if op == "-":
        return _add(left, right, -1.0)
    if op == ".":
        return _dot(left, right)
    if op in ("AND", "OR"):
        return _logic(left, right, op)
    raise OperandError(f"unknown operator {op!r}")


def unary(op: str, operand: Value) -> Value:
    """Apply ``-``, ``+`` (scalars, vectors) or ``NOT`` (booleans)."""
    if op == "NOT":
        if isinstance(operand, bool):
            return not operand
        raise OperandError(f"NOT needs a boolean, not {typed(operand)}")
    if isinstance(operand, Scalar):
        return operand if op == "+" else Scalar(-operand.value, operand.dim)
    if isinstance(operand, Vector):
        return operand if op == "+" else Vector(-operand.value, operand.dim)
    raise OperandError(f"unary '{op}' needs a scalar or a vector, not {typed(operand)}")


_RELATIONS: dict[str, Callable[[float, float], bool]] = {
    "<": lambda x, y: x < y,
    ">": lambda x, y: x > y,
    "=": lambda x, y: x == y,
    "≤": lambda x, y: x <= y,
    "≥": lambda x, y: x >= y,
    "≠": lambda x, y: x != y,
}


def compare(op: str, left: Value, right: Value) -> bool:
    """``left op right`` for one relation ``< > = ≤ ≥ ≠`` (scalars; ``=``/``≠`` also booleans).

    Equality of scalars is exact, as in AL; tests against a tolerance are the program's business
    (``ABS(DISTANCE_OFF) > .169``).
    """
    if op not in _RELATIONS:
        raise OperandError(f"unknown relation {op!r}")
    if isinstance(left, Scalar) and isinstance(right, Scalar):
        x, y, _ = scalar_pair(left, right, op)
        return _RELATIONS[op](x, y)
    if isinstance(left, bool) and isinstance(right, bool) and op in ("=", "≠"):
        return (left == right) == (op == "=")
    raise OperandError(f"cannot compare {typed(left)} with {typed(right)} by '{op}'")


def magnitude(value: Value) -> Scalar:
    """``|x|``: absolute value, Euclidean norm, or the angle of a rotation (PNT77)."""
    if isinstance(value, Scalar):
        return Scalar(abs(value.value), value.dim)
    if isinstance(value, Vector):
        return Scalar(float(np.linalg.norm(value.value)), value.dim)
    if isinstance(value, Rotation):
        return Scalar(float(np.linalg.norm(pin.log3(value.matrix))), ANGLE)
    raise OperandError(f"|x| needs a scalar, vector or rotation, not {typed(value)}")
