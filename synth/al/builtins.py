"""AL's builtin functions and predeclared names: ROT, TRANS, VECTOR, …; CM, ZHAT, TRUE, ….

**Builtins** (:data:`BUILTINS`): ``ROT(axis, angle)`` = ``ROTN`` (the axis is normalised;
S:2723 writes ``VECTOR(.924,.383,.001)``), ``TRANS(r, v)``, ``FRAME(r, v)``,
``VECTOR(x, y, z)``, ``INV(f | t | r)`` (frame and trans → trans), ``ORIENT(f)`` → r,
``DISPL(f)`` = ``POS(f)`` → v, ``ABS``, ``SQRT``, ``SIN``, ``COS``, ``TAN``, ``ATAN2(y, x)``.
``FORCE``, ``TORQUE`` and ``OPENING`` read sensors and live in the interpreter.

**Predeclared names** (:data:`CONSTANTS`): the unit constants (:data:`UNITS`, seed-al-subset.md
§1), the axes and identities (``XHAT``, ``NILROTN``, ``NILTRANS``, …) and ``TRUE``/``FALSE``;
the interpreter keeps them read-only.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from synth.al.values import (
    ANGLE,
    DIMENSIONLESS,
    FORCE,
    LENGTH,
    TIME,
    OperandError,
    Pose,
    PoseKind,
    Rotation,
    Scalar,
    Value,
    Vector,
    coerce,
    length_of,
    scalar_pair,
    typed,
)
from synth.units import CM, DEG, INCH, OZ

__all__ = ["BUILTINS", "CONSTANTS", "UNITS", "call_builtin", "rotation_about"]


def _arity(name: str, args: Sequence[Value], n: int) -> None:
    if len(args) != n:
        raise OperandError(f"{name} takes {n} argument{'s' if n != 1 else ''}, not {len(args)}")


def _want(name: str, value: Value, kind: type | tuple[type, ...], what: str) -> None:
    if not isinstance(value, kind) or isinstance(value, bool):
        raise OperandError(f"{name} needs {what}, not {typed(value)}")


def rotation_about(axis: ArrayLike, angle: float) -> Rotation:
    """Rotation by ``angle`` [rad] about ``axis`` (any non-zero vector; normalised)."""
    a = np.asarray(axis, dtype=float)
    largest = float(np.max(np.abs(a)))
    if not math.isfinite(largest):
        raise OperandError("a rotation axis must be a finite vector")
    if largest > 0.0:
        a = a / largest  # |(1e200, 0, 0)|² overflows: its direction does not
    norm = float(np.linalg.norm(a))
    if norm * largest < 1e-12:
        raise OperandError("a rotation axis must be a non-zero vector")
    return Rotation(pin.exp3(a / norm * angle))


def _rot(name: str, args: Sequence[Value]) -> Value:
    _arity(name, args, 2)
    axis, angle = args
    _want(name, axis, Vector, "an axis vector first")
    _want(name, angle, Scalar, "an angle second")
    assert isinstance(axis, Vector) and isinstance(angle, Scalar)
    return rotation_about(axis.value, coerce(angle, ANGLE, f"the angle of {name}").value)


def _pose(kind: PoseKind) -> Callable[[str, Sequence[Value]], Value]:
    def build(name: str, args: Sequence[Value]) -> Value:
        _arity(name, args, 2)
        rot, vec = args
        _want(name, rot, Rotation, "a rotation first")
        _want(name, vec, Vector, "a vector second")
        assert isinstance(rot, Rotation) and isinstance(vec, Vector)
        return Pose(pin.SE3(rot.matrix, length_of(vec, f"the vector of {name}")), kind)

    return build


def _vector(name: str, args: Sequence[Value]) -> Value:
    _arity(name, args, 3)
    for a in args:
        _want(name, a, Scalar, "three scalars")
    scalars = [a for a in args if isinstance(a, Scalar)]
    dims = {s.dim for s in scalars if not s.dim.dimensionless}
    if len(dims) > 1:
        shown = ", ".join(sorted(d.name for d in dims))
        raise OperandError(f"VECTOR components must share one dimension, not {shown}")
    dim = dims.pop() if dims else DIMENSIONLESS
    return Vector(np.array([coerce(s, dim).value for s in scalars]), dim)


def _inv(name: str, args: Sequence[Value]) -> Value:
    _arity(name, args, 1)
    (x,) = args
    if isinstance(x, Pose):
        return Pose(x.se3.inverse(), "trans")
    if isinstance(x, Rotation):
        return Rotation(x.matrix.T)
    raise OperandError(f"INV needs a frame, trans or rotation, not {typed(x)}")


def _orient(name: str, args: Sequence[Value]) -> Value:
    _arity(name, args, 1)
    (x,) = args
    _want(name, x, Pose, "a frame or trans")
    assert isinstance(x, Pose)
    return Rotation(x.se3.rotation)


def _displ(name: str, args: Sequence[Value]) -> Value:
    _arity(name, args, 1)
    (x,) = args
    _want(name, x, Pose, "a frame or trans")
    assert isinstance(x, Pose)
    return Vector(x.se3.translation, LENGTH)


def _scalar_fn(fn: Callable[[Scalar], Scalar]) -> Callable[[str, Sequence[Value]], Value]:
    def call(name: str, args: Sequence[Value]) -> Value:
        _arity(name, args, 1)
        (x,) = args
        _want(name, x, Scalar, "a scalar")
        assert isinstance(x, Scalar)
        return fn(x)

    return call


def _sqrt(x: Scalar) -> Scalar:
    if x.value < 0:
        raise OperandError("SQRT of a negative number")
    return Scalar(math.sqrt(x.value), x.dim.sqrt())


def _trig(fn: Callable[[float], float]) -> Callable[[Scalar], Scalar]:
    return lambda x: Scalar(fn(coerce(x, ANGLE, "a trigonometric argument").value))


def _atan2(name: str, args: Sequence[Value]) -> Value:
    _arity(name, args, 2)
    for a in args:
        _want(name, a, Scalar, "two scalars")
    y, x = args
    assert isinstance(y, Scalar) and isinstance(x, Scalar)
    yv, xv, _ = scalar_pair(y, x, "ATAN2")
    return Scalar(math.atan2(yv, xv), ANGLE)


Builtin = Callable[[str, Sequence[Value]], Value]

BUILTINS: dict[str, Builtin] = {
    "ROT": _rot,
    "ROTN": _rot,
    "TRANS": _pose("trans"),
    "FRAME": _pose("frame"),
    "VECTOR": _vector,
    "INV": _inv,
    "ORIENT": _orient,
    "DISPL": _displ,
    "POS": _displ,
    "ABS": _scalar_fn(lambda x: Scalar(abs(x.value), x.dim)),
    "SQRT": _scalar_fn(_sqrt),
    "SIN": _scalar_fn(_trig(math.sin)),
    "COS": _scalar_fn(_trig(math.cos)),
    "TAN": _scalar_fn(_trig(math.tan)),
    "ATAN2": _atan2,
}
"""Pure functions by upper-case AL name (see the module docstring)."""


def call_builtin(name: str, args: Sequence[Value]) -> Value:
    """Call the builtin ``name`` (upper case) on evaluated ``args``."""
    fn = BUILTINS.get(name)
    if fn is None:
        raise OperandError(f"unknown function {name}")
    return fn(name, args)


# --------------------------------------------------------------------------------------------
# Predeclared constants

UNITS: dict[str, Scalar] = {
    "CM": Scalar(CM, LENGTH),
    "MM": Scalar(0.001, LENGTH),
    "INCHES": Scalar(INCH, LENGTH),
    "INCH": Scalar(INCH, LENGTH),
    "IN": Scalar(INCH, LENGTH),
    "DEG": Scalar(DEG, ANGLE),
    "DEGREES": Scalar(DEG, ANGLE),
    "RAD": Scalar(1.0, ANGLE),
    "SEC": Scalar(1.0, TIME),
    "OZ": Scalar(OZ, FORCE),
    "LBS": Scalar(16.0 * OZ, FORCE),
    "GM": Scalar(0.001 * 9.80665, FORCE),
}
"""Unit constants (seed-al-subset.md §1, al-language.md §1); OZ, LBS and GM are forces."""

CONSTANTS: dict[str, Value] = {
    **UNITS,
    "XHAT": Vector(np.array([1.0, 0.0, 0.0])),
    "YHAT": Vector(np.array([0.0, 1.0, 0.0])),
    "ZHAT": Vector(np.array([0.0, 0.0, 1.0])),
    "NILVECT": Vector(np.array([0.0, 0.0, 0.0])),
    "NILROTN": Rotation(np.eye(3)),
    "NILROT": Rotation(np.eye(3)),
    "NILTRANS": Pose(pin.SE3.Identity(), "trans"),
    "TRUE": True,
    "FALSE": False,
}
"""Predeclared read-only names (S:1223, S:1264, S:1338, S:2693)."""
