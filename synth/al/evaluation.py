"""AL expressions: evaluation, sensing and assignment, for the interpreter.

The semantics are the interpreter's (its module docstring): a name with no value is an error,
never 0; assignment is an expression and declares an undeclared name as a global typed by its
first value; ``FORCE(v)``/``TORQUE(v)`` read the machine's wrist sensor along the world
direction v (``FORCE(frame*v)`` is ``FORCE(ORIENT(frame)*v)``, S:1376 vs S:2735); ``OPENING``
reads the finger opening. Each expression node type has one method, dispatched by node type
(:data:`_EXPRESSIONS`). A mix-in: the interpreter supplies the machine, the global scope and
the error maker.
"""

from __future__ import annotations

import contextlib
import itertools
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from synth.al import ast
from synth.al.builtins import CONSTANTS, call_builtin
from synth.al.frames import Scope, Variable, set_pose
from synth.al.process import ProcessContext
from synth.al.values import (
    FORCE,
    LENGTH,
    TORQUE,
    Event,
    Exponents,
    OperandError,
    Pose,
    Rotation,
    Scalar,
    Value,
    Vector,
    binary,
    coerce,
    compare,
    magnitude,
    type_name,
    unary,
)

if TYPE_CHECKING:
    from synth.al.machine import Machine
    from synth.exceptions import ALRuntimeError

__all__ = ["SENSORS", "Evaluation"]

SENSORS = frozenset({"FORCE", "TORQUE"})
"""The wrist sensor's functions: read in expressions, watched by monitors, held by WITH."""


class Evaluation:
    """Expression evaluation and assignment (a mix-in of the interpreter; module docstring)."""

    if TYPE_CHECKING:
        machine: Machine
        _global: Scope

        def _error(self, node: ast.Node | None, problem: str) -> ALRuntimeError: ...
        def _check_declarable(self, name: str, node: ast.Node | None) -> None: ...
        def _refused_at(self, node: ast.Node | None) -> contextlib.AbstractContextManager[None]: ...

    def _arithmetic(self, node: ast.Node, op: str, left: Value, right: Value) -> Value:
        try:
            if isinstance(left, Vector) or isinstance(right, Vector):
                # numpy warns of an overflow; _finite says it, at its line
                with np.errstate(over="ignore", invalid="ignore"):
                    result = binary(op, left, right)
            else:
                result = binary(op, left, right)
            return self._finite(node, result)
        except OperandError as problem:
            raise self._error(node, str(problem)) from None

    def _finite(self, node: ast.Node, value: Any) -> Any:
        """``value``, or an AL runtime error at ``node`` when a number in it is not finite.

        Floats overflow silently: ``1e200*1e200`` was infinity and ``A − A`` NaN, and a NaN pose
        crashed the arm's inverse kinematics (the fourth hunt); ``1/0`` already was an error.
        """
        if isinstance(value, Scalar):
            finite = math.isfinite(value.value)
        elif isinstance(value, Vector):
            # an inf or NaN entry makes the sum so (finite entries overflow it only near 1e308)
            finite = math.isfinite(value.value.sum())
        elif isinstance(value, Rotation):
            finite = math.isfinite(value.matrix.sum())
        else:  # a frame or trans of finite parts (the motion refuses one a kilometre away)
            return value
        if not finite:
            raise self._error(node, "the result is not a finite number (the arithmetic overflowed)")
        return value

    def _direction(self, call: ast.Call, cx: ProcessContext) -> tuple[float, float, float]:
        """The world unit direction of FORCE(v)/TORQUE(v); ``frame*v`` uses the rotation only."""
        if len(call.args) != 1:
            raise self._error(call, f"{call.func.name} takes one direction vector")
        (arg,) = call.args
        value: Value
        if isinstance(arg, ast.BinOp) and arg.op == "*":
            left, right = self._eval(arg.left, cx), self._eval(arg.right, cx)
            if isinstance(left, Pose) and isinstance(right, Vector):
                value = Vector(left.se3.rotation @ right.value, right.dim)
            else:
                value = self._apply(arg, lambda: binary("*", left, right))
        else:
            value = self._eval(arg, cx)
        if not isinstance(value, Vector):
            raise self._error(arg, f"{call.func.name} needs a direction vector")
        norm = float(np.linalg.norm(value.value))
        if norm < 1e-12:
            raise self._error(arg, f"{call.func.name} needs a non-zero direction")
        x, y, z = (float(v) for v in value.value / norm)
        return (x, y, z)

    def _eval(self, e: ast.Expr, cx: ProcessContext) -> Value:
        method = _EXPRESSIONS.get(type(e))
        if method is None:
            raise self._error(e, f"cannot evaluate {type(e).__name__}")
        return method(self, e, cx)

    def _apply(self, node: ast.Node, fn: Callable[[], Any]) -> Any:
        try:
            return self._finite(node, fn())
        except OperandError as problem:
            raise self._error(node, str(problem)) from None

    def _number(self, e: ast.Number, cx: ProcessContext) -> Value:
        return Scalar(e.value)

    def _string(self, e: ast.String, cx: ProcessContext) -> Value:
        return e.value

    def _name(self, e: ast.Name, cx: ProcessContext) -> Value:
        return self._read(e, cx)

    def _read(self, e: ast.Name, cx: ProcessContext) -> Value:
        variable = cx.scope.lookup(e.name)
        if variable is not None:
            if variable.value is None:
                raise self._error(e, f"{e.name} has no value yet")
            return variable.value
        constant = CONSTANTS.get(e.name)
        if constant is not None:
            return constant
        if e.name == "OPENING":
            return Scalar(self.machine.opening(), LENGTH)
        if e.name in ("ARRIVAL", "DURATION"):
            raise self._error(e, f"{e.name} is only meaningful in an ON or WITH clause")
        raise self._error(e, f"unknown name {e.name}")

    def _call(self, e: ast.Call, cx: ProcessContext) -> Value:
        name = e.func.name
        if name in SENSORS:
            direction = np.array(self._direction(e, cx))
            if name == "FORCE":
                return Scalar(self.machine.force(direction), FORCE)
            return Scalar(self.machine.torque(direction), TORQUE)
        args = [self._eval(a, cx) for a in e.args]
        return self._apply(e, lambda: call_builtin(name, args))  # type: ignore[no-any-return]

    def _unary(self, e: ast.UnaryOp, cx: ProcessContext) -> Value:
        operand = self._eval(e.operand, cx)
        return self._apply(e, lambda: unary(e.op, operand))  # type: ignore[no-any-return]

    def _binary(self, e: ast.BinOp, cx: ProcessContext) -> Value:
        left = self._eval(e.left, cx)
        right = self._eval(e.right, cx)
        return self._arithmetic(e, e.op, left, right)

    def _compare(self, e: ast.Compare, cx: ProcessContext) -> Value:
        values = [self._eval(x, cx) for x in e.operands]
        result = True
        pairs = zip(itertools.pairwise(values), e.ops, e.conjuncts(), strict=True)
        for (left, right), op, pair in pairs:
            try:
                held = compare(op, left, right)
            except OperandError as problem:
                raise self._error(pair, str(problem)) from None
            result = result and held
        return result

    def _magnitude(self, e: ast.Magnitude, cx: ProcessContext) -> Value:
        operand = self._eval(e.operand, cx)
        return self._apply(e, lambda: magnitude(operand))  # type: ignore[no-any-return]

    def _assign_expr(self, e: ast.AssignExpr, cx: ProcessContext) -> Value:
        value = self._eval(e.value, cx)
        self._store(e.target, value, cx)
        return value

    def _condition(self, e: ast.Expr, cx: ProcessContext) -> bool:
        value = self._eval(e, cx)
        if not isinstance(value, bool):
            raise self._error(e, f"a condition must be a boolean, not {type_name(value)}")
        return value

    def _scalar(self, e: ast.Expr, cx: ProcessContext, what: str) -> Scalar:
        value = self._eval(e, cx)
        if not isinstance(value, Scalar):
            raise self._error(e, f"{what} must be a scalar, not {type_name(value)}")
        return value

    def _dimensioned(self, e: ast.Expr, cx: ProcessContext, dim: Exponents, what: str) -> float:
        value = self._scalar(e, cx, what)
        return self._apply(e, lambda: coerce(value, dim, what).value)  # type: ignore[no-any-return]

    def _event(self, name: ast.Name, cx: ProcessContext) -> Event:
        variable = cx.scope.lookup(name.name)
        if variable is None:
            self._check_declarable(name.name, name)
            variable = Variable(name.name, "EVENT", Event(name.name))
            self._global.variables[name.name] = variable
        if not isinstance(variable.value, Event):
            raise self._error(name, f"{name.name} is a {variable.type.lower()}, not an event")
        return variable.value

    def _store(self, target: ast.Name, value: Value, cx: ProcessContext) -> None:
        variable = cx.scope.lookup(target.name)
        if variable is None:
            self._check_declarable(target.name, target)
            kind = _type_of(value)
            if kind == "EVENT":
                raise self._error(target, "an event cannot be assigned")
            variable = Variable(target.name, kind)
            self._global.variables[target.name] = variable
        if variable.hand:
            raise self._error(
                target, f"{target.name} is the arm's sensed hand frame; move it with MOVE"
            )
        wanted = variable.type
        if wanted in ("FRAME", "TRANS"):
            if not isinstance(value, Pose):
                raise self._error(
                    target, f"cannot assign {type_name(value)} to {wanted.lower()} {target.name}"
                )
            with self._refused_at(target):
                set_pose(variable, value.se3)
            return
        if _type_of(value) != wanted:
            raise self._error(
                target, f"cannot assign {type_name(value)} to {wanted.lower()} {target.name}"
            )
        variable.value = value


def _type_of(value: Value) -> str:
    name = type_name(value)
    return {"boolean": "BOOLEAN", "rot": "ROT"}.get(name, name.upper())


_Expression = Callable[[Evaluation, Any, ProcessContext], Value]

_EXPRESSIONS: dict[type, _Expression] = {
    ast.Number: Evaluation._number,
    ast.String: Evaluation._string,
    ast.Name: Evaluation._name,
    ast.Call: Evaluation._call,
    ast.UnaryOp: Evaluation._unary,
    ast.BinOp: Evaluation._binary,
    ast.Compare: Evaluation._compare,
    ast.Magnitude: Evaluation._magnitude,
    ast.AssignExpr: Evaluation._assign_expr,
}
