"""AL motion statements: MOVE, OPEN, CLOSE and CENTER become the machine's motions.

For :class:`~synth.al.interpreter.Interpreter` (its module docstring states the semantics,
S:1341, S:1185–1196): the destination, the via points, the ``WITH`` constraints and the ``ON``
thresholds and directions are evaluated first, in that textual order; a frame affixed to the
hand moves the hand by its relation; ``ON`` clauses become monitor specs
(:data:`~synth.al.machine.MonitorSpec`) and ``WITH`` clauses motion constraints, both as data;
a firing runs its handler at that instant, ``STOP`` ends the motion, and ``ON ARRIVAL``
handlers run after a motion that reached its last target unstopped. A mix-in: the interpreter
supplies statement execution, the hand frame and the active motion.
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Iterator
from typing import TYPE_CHECKING, cast

import pinocchio as pin

from synth.al import ast
from synth.al.evaluation import SENSORS, Evaluation
from synth.al.frames import Variable, se3_of
from synth.al.machine import (
    DurationConstraint,
    DurationMonitor,
    EventMonitor,
    ForceConstraint,
    ForceMonitor,
    MonitorSpec,
    MotionConstraint,
    MotionResult,
    OpeningMonitor,
    Relation,
    TorqueConstraint,
    TorqueMonitor,
)
from synth.al.process import Aborted, MotionState, ProcessContext
from synth.al.timeline import duration_conflict
from synth.al.values import FORCE, LENGTH, TIME, TORQUE, Pose, Value, type_name

__all__ = ["Motions"]

_FLIP: dict[str, Relation] = {"<": ">", ">": "<", "≤": "≥", "≥": "≤", "=": "=", "≠": "≠"}


class Motions(Evaluation):
    """Motion statements and their clauses (a mix-in of the interpreter; module docstring)."""

    if TYPE_CHECKING:
        hand_names: tuple[str, ...]
        _hand: Variable
        _active: MotionState | None

        def _exec(self, statement: ast.Stmt, cx: ProcessContext) -> Generator[None, None, None]: ...
        def _release_machine(self) -> None: ...
        def _sync_hand(self, pose: pin.SE3) -> None: ...

    def _move(self, s: ast.Move, cx: ProcessContext) -> Iterator[None]:
        moved = cx.scope.lookup(s.frame.name)
        if moved is None:
            raise self._error(s.frame, f"unknown name {s.frame.name}: MOVE needs a frame")
        if moved.type not in ("FRAME", "TRANS"):
            raise self._error(s.frame, f"MOVE needs a frame, and {s.frame.name} is a {moved.type}")
        hand_from_frame = self._hand_from(moved, s)
        points: list[tuple[ast.Expr, Value]] = [(s.destination, self._eval(s.destination, cx))]
        points += [(p, self._eval(p, cx)) for p in s.via_points]
        poses: list[pin.SE3] = []
        for expr, value in points:
            if not isinstance(value, Pose):
                raise self._error(expr, f"a motion goes to a frame, not to {type_name(value)}")
            poses.append(value.se3)
        frame_from_hand = hand_from_frame.inverse()
        targets = [p * frame_from_hand for p in (*poses[1:], poses[0])]
        yield from self._motion(s, cx, lambda m, c: self.machine.move(targets, m, c, s.line))

    def _hand_from(self, moved: Variable, s: ast.Move) -> pin.SE3:
        if moved.hand:
            return pin.SE3.Identity()
        node: Variable | None = moved
        while node is not None and not node.hand:
            node = node.link.parent if node.link is not None else None
        if node is None:
            raise self._error(
                s.frame,
                f"cannot move {moved.name}: it is not affixed to the hand "
                f"(AFFIX {moved.name} TO {self.hand_names[0]} first)",
            )
        if moved.pose is None:
            raise self._error(s.frame, f"{moved.name} has no value")
        return se3_of(self._hand.pose).inverse() * se3_of(moved.pose)

    def _device(self, name: ast.Name) -> None:
        if name.name not in self.hand_names:
            shown = ", ".join(self.hand_names)
            raise self._error(name, f"{name.name} is not a hand (the hand is {shown})")

    def _open(self, s: ast.Open, cx: ProcessContext) -> Iterator[None]:
        self._device(s.device)
        width = self._dimensioned(s.width, cx, LENGTH, "an opening")
        yield from self._motion(s, cx, lambda m, c: self.machine.open_hand(width, m, c, s.line))

    def _close(self, s: ast.Close, cx: ProcessContext) -> Iterator[None]:
        self._device(s.device)
        width = None
        if s.width is not None:
            width = self._dimensioned(s.width, cx, LENGTH, "an opening")
        yield from self._motion(s, cx, lambda m, c: self.machine.close_hand(width, m, c, s.line))

    def _center(self, s: ast.Center, cx: ProcessContext) -> Iterator[None]:
        self._device(s.device)
        yield from self._motion(s, cx, lambda m, c: self.machine.center(m, c, s.line))

    def _motion(
        self,
        s: ast.Move | ast.Open | ast.Close | ast.Center,
        cx: ProcessContext,
        start: Callable[[list[MonitorSpec], list[MotionConstraint]], MotionResult],
    ) -> Iterator[None]:
        """Run a motion statement: its clauses, the machine's motion, its handlers.

        The WITH clauses, then the ON clauses, are read; ``start`` begins the motion with the
        monitors and constraints; handlers run as the machine reports firings, then the ON
        ARRIVAL handlers.
        """
        constraints = self._constraints(s, cx)
        monitors, handlers, arrivals = self._monitors(s, cx)
        if self._active is not None:
            raise self._error(
                s, "a motion statement in a monitor body needs STOP first: the arm is still moving"
            )
        state = MotionState()
        result = start(monitors, constraints)
        self._active = state
        reported: set[int] = set()
        try:
            while True:
                self._sync_hand(result.hand_pose)
                if result.fired is None:
                    break
                index = result.fired
                if index in reported or not 0 <= index < len(handlers):
                    raise RuntimeError(
                        f"the machine reported monitor {index} wrongly (line {s.line})"
                    )
                reported.add(index)
                yield from self._exec(handlers[index], ProcessContext(cx.scope, state))
                if state.stopped:
                    break
                try:
                    result = self.machine.resume()
                except Exception:
                    self._active = None  # the machine ended the motion by failing
                    raise
        except Aborted:
            self._release_machine()
            raise
        self._active = None
        arrived = result.arrived and not state.stopped
        state.finished = True
        if arrived:
            for body in arrivals:
                yield from self._exec(body, ProcessContext(cx.scope, state))

    def _monitors(
        self, s: ast.Move | ast.Open | ast.Close | ast.Center, cx: ProcessContext
    ) -> tuple[list[MonitorSpec], list[ast.Stmt], list[ast.Stmt]]:
        monitors: list[MonitorSpec] = []
        handlers: list[ast.Stmt] = []
        arrivals: list[ast.Stmt] = []
        for on in s.monitors:
            condition = on.condition
            if isinstance(condition, ast.Name) and condition.name == "ARRIVAL":
                arrivals.append(on.body)
                continue
            monitors.append(self._monitor(condition, cx, on.line))
            handlers.append(on.body)
        return monitors, handlers, arrivals

    def _monitor(self, condition: ast.Expr, cx: ProcessContext, line: int) -> MonitorSpec:
        if isinstance(condition, ast.Name):
            self._event(condition, cx)
            return EventMonitor(condition.name, line)
        if isinstance(condition, ast.Compare) and len(condition.ops) == 1:
            (left, right), relation = condition.operands, _relation(condition.ops[0])
            if not _is_sensor(left) and _is_sensor(right):
                left, right, relation = right, left, _FLIP[relation]
            if isinstance(left, ast.Call) and left.func.name in SENSORS:
                direction = self._direction(left, cx)
                if left.func.name == "FORCE":
                    threshold = self._dimensioned(right, cx, FORCE, "a force threshold")
                    return ForceMonitor(direction, relation, threshold, line)
                threshold = self._dimensioned(right, cx, TORQUE, "a torque threshold")
                return TorqueMonitor(direction, relation, threshold, line)
            if isinstance(left, ast.Name) and left.name == "OPENING":
                threshold = self._dimensioned(right, cx, LENGTH, "an opening threshold")
                return OpeningMonitor(relation, threshold, line)
            if isinstance(left, ast.Name) and left.name == "DURATION":
                threshold = self._dimensioned(right, cx, TIME, "a duration")
                return DurationMonitor(relation, threshold, line)
        raise self._error(
            condition,
            "a monitor watches FORCE(v), TORQUE(v), OPENING or DURATION against a value, "
            "an event, or ARRIVAL",
        )

    def _constraints(
        self, s: ast.Move | ast.Open | ast.Close | ast.Center, cx: ProcessContext
    ) -> list[MotionConstraint]:
        out: list[MotionConstraint] = []
        written: list[ast.Expr] = []
        targets = 0
        previous: ast.Clause | None = None
        for clause in s.clauses:
            if isinstance(clause, ast.ViaClause):
                targets += len(clause.points)
            elif isinstance(clause, ast.WithClause):
                segment = targets - 1 if isinstance(previous, ast.ViaClause) else None
                out += [self._constraint(c, cx, segment) for c in clause.conditions]
                written += clause.conditions
            previous = clause
        conflict = duration_conflict(out)
        if conflict is not None:
            bound, later = conflict
            raise self._error(
                next(w for w, c in zip(written, out, strict=True) if c is later),
                f"DURATION {later.relation} {later.seconds:g} s contradicts DURATION "
                f"{bound.relation} {bound.seconds:g} s (line {bound.line}) for the same motion: "
                "no time meets both",
            )
        return out

    def _constraint(self, c: ast.Expr, cx: ProcessContext, segment: int | None) -> MotionConstraint:
        if isinstance(c, ast.Compare) and len(c.ops) == 1:
            (left, right), relation = c.operands, _relation(c.ops[0])
            if not _is_sensor(left) and _is_sensor(right):
                left, right, relation = right, left, _FLIP[relation]
            if isinstance(left, ast.Call) and left.func.name in SENSORS and relation == "=":
                direction = self._direction(left, cx)
                if left.func.name == "FORCE":
                    value = self._dimensioned(right, cx, FORCE, "a force")
                    return ForceConstraint(direction, value, segment, c.line)
                value = self._dimensioned(right, cx, TORQUE, "a torque")
                return TorqueConstraint(direction, value, segment, c.line)
            if isinstance(left, ast.Name) and left.name == "DURATION":
                seconds = self._dimensioned(right, cx, TIME, "a duration")
                if relation in ("=", "<", "≤") and not seconds > 0.0:
                    # the timeline would run the motion in no time or backwards
                    raise self._error(
                        c, f"DURATION {relation} {seconds:g} s: a motion takes a positive time"
                    )
                return DurationConstraint(relation, seconds, segment, c.line)
        raise self._error(c, "a WITH condition is FORCE(v) = f, TORQUE(v) = t or DURATION rel t")


def _relation(op: str) -> Relation:
    if op not in _FLIP:
        raise ValueError(f"unknown relation {op!r}")
    return cast(Relation, op)


def _is_sensor(e: ast.Expr) -> bool:
    if isinstance(e, ast.Call):
        return e.func.name in SENSORS
    return isinstance(e, ast.Name) and e.name in ("OPENING", "DURATION")
