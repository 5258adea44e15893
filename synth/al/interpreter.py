"""Run a parsed AL program against a :class:`~synth.al.machine.Machine`.

The interpreter owns the program's beliefs: its variables, their block scopes and the
affixment graph (kept consistent by :mod:`synth.al.frames`). It learns about the world only
through the machine (where the hand really is, what it senses, the finger opening, the clock).
It never looks at a true world itself.
Each statement and expression node type has one method, dispatched by node type. Each method
visits its children explicitly, because loops, branches and monitors decide what runs and when
(the ``lark.visitors.Interpreter`` style, applied to the dataclass AST of
:mod:`synth.al.ast`). This module runs the statements; the expressions' methods are
:mod:`synth.al.evaluation`'s and the motion statements' :mod:`synth.al.motion_statements`'s,
mix-ins of :class:`Interpreter` that share one process state (:mod:`synth.al.process`).

Semantics, with the seed's lines (S:n) and seed-al-subset.md sections:

**Names and scopes.** A block's declarations, wherever they appear in it, are made when the block is
entered (al-language.md §3). A block's names are released when it ends. Its frames leave the
affixment graph: their links are cut, and frames affixed to them keep their values (S:245). A
program's top-level statements run in the *global* scope, which also holds the world binding
(:mod:`synth.codegen.binding`). A top-level declaration of a frame the binding holds, with the
binding's type, adopts that frame once (a stand-alone program declares the task's frames
itself, ``synth plan --preamble``); declaring it again is an error. Assigning a name that is
declared nowhere declares it implicitly in the global scope, typed by its first value:
generated programs never declare ``DISTANCE_OFF``, ``CORR`` or ``PIN1`` (S:2737, S:2827).
Reading a name with no value is an error.
No value defaults to 0: a referee should not invent one. Predeclared names (units, ``XHAT``,
``NILROTN``, ``TRUE``, ...) are read-only. So are the arm's hand names (``BLUE``, ``BMANIP``,
``BARM``, ``BHAND``, ``BFINGERS``: one frame, the sensed hand, moved only by ``MOVE``).

**Affixment** (S:1160–1200, S:1466–1480; seed-al-subset.md §4). Each frame has at most one
parent. ``AFFIX A TO B AT T`` sets A ← B*T now and whenever B changes. Without ``AT``, T is the
current INV(B)*A. Affixing A again replaces its old link, and a cycle is an error. Chains are
transitive. ``RIGIDLY``: assigning A also moves B (B ← A*INV(T)), and with B everything else
affixed to it (S:1473–1477). Rigid links are followed upwards as far as they go. ``UNFIX A
FROM B`` (either order, S:1327 vs S:1500) cuts the link, and A keeps its value. Undeclared
names in AFFIX are declared implicitly as global frames, possibly still without a value: the
seed affixes to ``pin_holder`` before assigning it (S:1554–1556).

*Decision (§7): assigning a non-rigidly affixed frame* keeps the new value and re-derives its
relation, T ← INV(B)*A, so it keeps following B from there. The parent does not move (that is
what ``RIGIDLY`` is for).

**Motion** (S:1341, S:1185–1196; §4–§5). ``MOVE F TO D VIA P1, ...``: D, the via points, the
``WITH`` constraints and the ``ON`` thresholds and directions are all evaluated first, in that
textual order, before the arm moves. ``MOVE BMANIP TO BMANIP*TRANS(...)`` is therefore relative
to the start. F is the hand or a frame affixed to it through a chain. With T = INV(hand)*F at
the start, the hand's targets are P_i*INV(T), then D*INV(T). After the motion, and at every
monitor firing, the hand frame is set to the machine's sensed pose and every frame affixed to
it follows. After an early stop, ``PIN1`` therefore holds where the pin really stopped
(seed-al-subset.md §5).

**Monitors.** ``ON FORCE(v) > f``, ``TORQUE(v) rel t``, ``OPENING rel w``, ``DURATION rel t``,
an event name, or ``ARRIVAL``. All but ``ARRIVAL`` go to the machine as data
(:data:`~synth.al.machine.MonitorSpec`). When the machine reports a firing, the handler runs at
that instant. ``STOP`` ends the motion there, and the rest of the handler still runs. Without a
``STOP``, the motion resumes. Execution continues after the motion statement either way.
*Decision (§7): each monitor fires at most once per motion.* ``ON ARRIVAL`` handlers run after a
motion that reached its last target with no handler having stopped it (S:1396–1399). ``ABORT``
in a handler stops the motion and ends the program. A motion statement inside a handler is
allowed only after ``STOP``, since the arm is still moving before it. The force direction is a
world direction. ``FORCE(frame*v)`` is read as ``FORCE(ORIENT(frame)*v)`` (S:1376 vs S:2735).
Bare thresholds are in AL's bare units (``OPENING < .185`` is 0.185 cm).

**Hand.** ``OPEN dev TO w``, ``CLOSE dev [TO w]`` and ``CENTER dev`` take any hand name as
device (S:1286, S:2722, S:1780). They are motions too: they take monitors and constraints, and
the hand frame is re-read afterwards, because ``CENTER`` moves the arm.

**Control** (ALGOL 60). ``IF``, ``WHILE`` and ``FOR v ← a STEP s UNTIL c``: v ← a; then, while
(v − c)·sign(s) ≤ 0, run the body and set v ← v + s. The step and the limit are re-evaluated
each time they are used, so assigning v in the body ends the loop (S:1532). Assignment is also
an expression: ``(n←n+1) ≤ 6``. *Decision (§7): AND and OR* take booleans and evaluate both
operands, left to right, as ALGOL 60 does; there is no short circuit, so side effects such as
``ABS(X←...) < a AND ABS(Y←...) < b`` always happen. A relation chain evaluates every operand
once.

**Budgets.** Three bounds turn a runaway program into a runtime error naming the statement
about to run: ``max_statements`` statements (default 10⁶), ``max_time`` of the machine's
simulated clock (default :data:`MAX_TIME`, 600 s: the seed's programs take seconds; a loop of
MOVEs passes it in about ten seconds of computing where the statement budget took 1.7 h) and
``max_wall_time`` of real time per run (default :data:`MAX_WALL_TIME`, 20 s, for loops of
motions that take no simulated time). The wall clock makes a run's outcome depend on the
computer only for a program that is already runaway. A program nested more than
:data:`~synth.al.ast.MAX_NESTING` levels deep is refused before it runs (evaluation recurses).

**Processes.** ``COBEGIN s1; s2; ... COEND`` interleaves its branches cooperatively, one
statement at a time per process. A branch runs until it finishes or blocks in ``WAIT``, then
the next branch runs. The ``COBEGIN`` ends when all branches have. If every branch is blocked
and nothing outside can signal, the result is a deadlock error at the ``WAIT``. Motions are
atomic with respect to other processes. *Decision (§7): events* may be declared (``EVENT e``,
block-scoped), or are declared implicitly as globals on first use. ``SIGNAL e`` adds one to the
event's count. ``WAIT e`` takes one, or blocks while the count is zero. An ``ON e`` monitor
fires only when the machine reports the event (an external sensor); signals from other
processes cannot reach a motion in progress.

**Outcome.** :meth:`Interpreter.run` returns a :class:`RunResult`. ``ABORT("...")`` is a normal
outcome (:class:`ALAbort`, with the message and the AL line), not an exception. A faulty
program raises :class:`~synth.exceptions.ALRuntimeError` with the AL line and column.
"""

from __future__ import annotations

import contextlib
import math
import time
import weakref
from collections.abc import Callable, Generator, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from synth.al import ast
from synth.al.builtins import CONSTANTS
from synth.al.frames import (
    Affixment,
    FrameError,
    Scope,
    Variable,
    affix,
    propagate,
    set_pose,
    unlink,
)
from synth.al.machine import (
    Machine,
)
from synth.al.motion_statements import Motions
from synth.al.names import ARM_NAMES, KEYWORDS
from synth.al.process import Aborted, ALAbort, MotionState, ProcessContext
from synth.al.values import (
    Event,
    Pose,
    Scalar,
    Value,
    describe,
    type_name,
)
from synth.exceptions import ALRuntimeError

_DEPTHS: dict[int, tuple[weakref.ref[ast.Program], ast.Node | None]] = {}


def _too_deep(program: ast.Program) -> ast.Node | None:
    """:func:`ast.too_deep` of ``program``, walked once per program object.

    A replay runs one program thousands of times, and the tree is immutable.
    """
    cached = _DEPTHS.get(id(program))
    if cached is not None and cached[0]() is program:
        return cached[1]
    deep = ast.too_deep(program)
    key = id(program)
    _DEPTHS[key] = (weakref.ref(program, lambda _: _DEPTHS.pop(key, None)), deep)
    return deep


__all__ = [
    "HAND_NAMES",
    "MAX_STATEMENTS",
    "MAX_TIME",
    "MAX_WALL_TIME",
    "ALAbort",
    "Affixment",
    "Interpreter",
    "RunResult",
    "run_program",
]

MAX_STATEMENTS = 1_000_000
"""Statements one run may execute."""
MAX_TIME = 600.0
"""[s] simulated time one run may take."""
MAX_WALL_TIME = 20.0
"""[s] real time one run may take."""


HAND_NAMES: tuple[str, ...] = ARM_NAMES
"""The blue arm's names (al-language.md §6): all denote its one hand frame and hand device."""


@dataclass(frozen=True)
class RunResult:
    """The outcome of a run.

    ``abort`` is None when the program ran to its end. ``statements`` counts the statements
    executed. ``time`` is the machine clock at the end [s].
    """

    abort: ALAbort | None
    statements: int
    time: float

    @property
    def completed(self) -> bool:
        """True when the program ran to its end without ``ABORT``."""
        return self.abort is None


# --------------------------------------------------------------------------------------------
# The interpreter


class Interpreter(Motions):
    """Executes AL programs on ``machine``; one instance holds one program's world model.

    ``hand_names`` are the names of the arm's hand (all one frame and one device).
    ``max_statements`` bounds the statements one :meth:`run` may execute, ``max_time`` [s] the
    simulated time it may take and ``max_wall_time`` [s] the real time (module docstring).
    """

    def __init__(
        self,
        machine: Machine,
        *,
        hand_names: Sequence[str] = HAND_NAMES,
        max_statements: int = MAX_STATEMENTS,
        max_time: float = MAX_TIME,
        max_wall_time: float = MAX_WALL_TIME,
    ) -> None:
        self.machine = machine
        self.max_statements = max_statements
        self.max_time = max_time
        self.max_wall_time = max_wall_time
        self._time_limit = math.inf  # [s] simulated clock at which the run is over budget
        self._wall_limit = math.inf  # [s] time.monotonic() at which it is
        self.hand_names = tuple(n.upper() for n in hand_names)
        for name in self.hand_names:
            if name in CONSTANTS or name in KEYWORDS:
                raise ValueError(f"{name} is predeclared in AL and cannot name the hand")
        self._global = Scope(None, "<global>")
        self._hand = Variable(self.hand_names[0], "FRAME", hand=True)
        for name in self.hand_names:
            self._global.variables[name] = self._hand
        self._filename = "<al>"
        self._statements = 0
        self._budget = max_statements
        self._signals = 0
        self._blocked: ast.Wait | None = None
        self._active: MotionState | None = None
        self._sync_hand(machine.hand_pose())

    # ---- public: binding and inspection

    def define_frame(self, name: str, pose: pin.SE3, kind: str = "FRAME") -> None:
        """Declare a global frame ``name`` with value ``pose`` [m] (the world binding)."""
        upper = name.upper()
        self._check_declarable(upper, None)
        if upper in self._global.variables:
            raise ValueError(f"{upper} is already bound")
        variable = Variable(upper, kind, bound=True)
        self._global.variables[upper] = variable
        with self._refused_at(None):
            set_pose(variable, pose)

    def affix(
        self, child: str, parent: str, parent_from_child: pin.SE3 | None = None, *, rigid: bool
    ) -> None:
        """``AFFIX child TO parent [RIGIDLY] [AT parent_from_child]`` on global frames."""
        c, p = self._global.lookup(child.upper()), self._global.lookup(parent.upper())
        if c is None or p is None:
            raise ValueError(f"affix {child} to {parent}: both must be bound first")
        with self._refused_at(None):
            affix(c, p, parent_from_child, rigid)

    def value(self, name: str) -> Value | None:
        """The value of global ``name`` (None if it has none); constants too."""
        upper = name.upper()
        variable = self._global.lookup(upper)
        if variable is not None:
            return variable.value
        return CONSTANTS.get(upper)

    def frame(self, name: str) -> pin.SE3:
        """The value of global frame ``name`` [m] (a copy)."""
        value = self.value(name)
        if not isinstance(value, Pose):
            raise KeyError(f"{name} is not a frame with a value")
        return pin.SE3(value.se3)

    def affixment(self, name: str) -> Affixment | None:
        """The link from global frame ``name`` to its parent, or None."""
        variable = self._global.lookup(name.upper())
        if variable is None or variable.link is None:
            return None
        link = variable.link
        return Affixment(
            variable.name, link.parent.name, pin.SE3(link.parent_from_child), link.rigid
        )

    # ---- running

    @property
    def statements(self) -> int:
        """Statements executed so far by this interpreter (also when a run ended by raising)."""
        return self._statements

    def run(self, program: ast.Program) -> RunResult:
        """Execute ``program``; returns its outcome, raises ALRuntimeError for a faulty one."""
        self._filename = program.filename
        deep = _too_deep(program)
        if deep is not None:
            raise self._error(deep, f"nested more than {ast.MAX_NESTING} levels deep")
        start = self._statements
        self._budget = start + self.max_statements
        self._time_limit = self.machine.time() + self.max_time
        self._wall_limit = time.monotonic() + self.max_wall_time
        context = ProcessContext(self._global)
        steps = self._sequence(program.body, context, declare_in=self._global)
        try:
            for _ in steps:
                self._deadlock()
        except Aborted as aborted:
            return RunResult(aborted.abort, self._statements - start, self.machine.time())
        finally:
            steps.close()
            self._release_machine()
        return RunResult(None, self._statements - start, self.machine.time())

    def _release_machine(self) -> None:
        active = self._active
        if active is not None and not active.stopped:
            active.stopped = True
            self.machine.stop()
            self._sync_hand(self.machine.hand_pose())
        self._active = None

    def _deadlock(self) -> None:
        wait = self._blocked
        assert wait is not None
        raise self._error(wait, f"WAIT {wait.event.name}: no process can signal it (deadlock)")

    # ---- errors

    def _error(self, node: ast.Node | None, problem: str) -> ALRuntimeError:
        line, column = (node.line, node.column) if node is not None else (0, 0)
        return ALRuntimeError(line, column, problem, filename=self._filename)

    # ---- statements

    def _sequence(
        self, body: Sequence[ast.Stmt], cx: ProcessContext, *, declare_in: Scope | None = None
    ) -> Generator[None, None, None]:
        if declare_in is not None:
            for statement in body:
                if isinstance(statement, ast.Declaration):
                    self._declare(statement, declare_in)
        for statement in body:
            yield from self._exec(statement, cx)

    def _exec(self, statement: ast.Stmt, cx: ProcessContext) -> Generator[None, None, None]:
        self._statements += 1
        if self._statements > self._budget:
            raise self._error(
                statement, f"more than {self.max_statements} statements executed (an endless loop?)"
            )
        if self.machine.time() > self._time_limit:
            raise self._error(
                statement,
                f"more than {self.max_time:g} s of simulated time (an endless loop of motions?)",
            )
        if time.monotonic() > self._wall_limit:
            raise self._error(
                statement,
                f"more than {self.max_wall_time:g} s of computing time for one run "
                "(an endless loop?)",
            )
        method = _STATEMENTS.get(type(statement))
        if method is None:
            raise self._error(statement, f"cannot execute {type(statement).__name__}")
        yield from method(self, statement, cx)

    def _block(self, s: ast.Block, cx: ProcessContext) -> Iterator[None]:
        scope = Scope(cx.scope, s.name or "<block>")
        try:
            yield from self._sequence(s.body, ProcessContext(scope, cx.motion), declare_in=scope)
        finally:
            self._release(scope)

    def _cobegin(self, s: ast.Cobegin, cx: ProcessContext) -> Iterator[None]:
        for statement in s.body:
            if isinstance(statement, ast.Declaration):
                self._declare(statement, cx.scope)
        branches = [b for b in s.body if not isinstance(b, ast.Declaration)]
        live = [self._exec(branch, cx) for branch in branches]
        try:
            while live:
                progress = False
                for branch in list(live):
                    signals = self._signals
                    try:
                        next(branch)
                    except StopIteration:
                        live.remove(branch)
                        progress = True
                        continue
                    progress = progress or self._signals != signals
                if live and not progress:
                    yield  # every branch waits: let an enclosing process signal
        finally:
            for branch in live:
                branch.close()

    def _declaration(self, s: ast.Declaration, cx: ProcessContext) -> Iterator[None]:
        return iter(())  # made when the block was entered

    def _declare(self, s: ast.Declaration, scope: Scope) -> None:
        for name in s.names:
            self._check_declarable(name.name, name)
            existing = scope.variables.get(name.name)
            if existing is not None and existing.bound:
                # A stand-alone program (``synth plan --preamble``) declares the task's frames
                # itself: the same name with the same type is the binding's frame, adopted once.
                if existing.type != s.type:
                    raise self._error(
                        name, f"{name.name} is the task's {existing.type}; it cannot be a {s.type}"
                    )
                existing.bound = False
                continue
            if existing is not None:
                raise self._error(name, f"{name.name} is declared twice in this block")
            variable = Variable(name.name, s.type)
            if s.type == "EVENT":
                variable.value = Event(name.name)
            scope.variables[name.name] = variable

    def _check_declarable(self, name: str, node: ast.Node | None) -> None:
        if name in self.hand_names:
            raise self._error(node, f"{name} is the arm's hand; it is predeclared")
        if name in CONSTANTS or name in KEYWORDS:
            raise self._error(node, f"{name} is predeclared in AL and cannot be redefined")

    def _release(self, scope: Scope) -> None:
        for variable in scope.variables.values():
            if variable.link is not None:
                unlink(variable)
            for child in list(variable.children):
                unlink(child)

    def _assign(self, s: ast.Assign, cx: ProcessContext) -> Iterator[None]:
        self._store(s.target, self._eval(s.value, cx), cx)
        return iter(())

    def _if(self, s: ast.If, cx: ProcessContext) -> Iterator[None]:
        if self._condition(s.condition, cx):
            yield from self._exec(s.then, cx)
        elif s.orelse is not None:
            yield from self._exec(s.orelse, cx)

    def _while(self, s: ast.While, cx: ProcessContext) -> Iterator[None]:
        while self._condition(s.condition, cx):
            yield from self._exec(s.body, cx)

    def _for(self, s: ast.For, cx: ProcessContext) -> Iterator[None]:
        # ALGOL 60 report 4.6.4.2: V := A; L1: if (V-C)*sign(B) > 0 goto done; S; V := V+B; goto L1
        self._store(s.variable, self._scalar(s.start, cx, "the FOR start"), cx)
        while True:
            step = self._scalar(s.step, cx, "the FOR step")
            limit = self._scalar(s.limit, cx, "the FOR limit")
            current = self._counter(s, cx)
            excess = self._arithmetic(s, "-", current, limit)
            assert isinstance(excess, Scalar)
            if excess.value * np.sign(step.value) > 0:
                return
            yield from self._exec(s.body, cx)
            step = self._scalar(s.step, cx, "the FOR step")
            current = self._counter(s, cx)
            self._store(s.variable, self._arithmetic(s, "+", current, step), cx)

    def _counter(self, s: ast.For, cx: ProcessContext) -> Scalar:
        value = self._read(s.variable, cx)
        if not isinstance(value, Scalar):
            raise self._error(s.variable, f"the FOR variable holds {type_name(value)}")
        return value

    def _signal(self, s: ast.Signal, cx: ProcessContext) -> Iterator[None]:
        self._event(s.event, cx).count += 1
        self._signals += 1
        return iter(())

    def _wait(self, s: ast.Wait, cx: ProcessContext) -> Iterator[None]:
        event = self._event(s.event, cx)
        while event.count == 0:
            self._blocked = s
            yield
        event.count -= 1

    def _abort(self, s: ast.Abort, cx: ProcessContext) -> Iterator[None]:
        message = "".join(describe(self._eval(a, cx)) for a in s.args)
        raise Aborted(ALAbort(message, s.line, s.column))

    def _stop(self, s: ast.Stop, cx: ProcessContext) -> Iterator[None]:
        motion = cx.motion
        if motion is None:
            raise self._error(s, "STOP outside a monitor body (ON ... DO STOP)")
        if not motion.stopped and not motion.finished:
            motion.stopped = True
            self.machine.stop()
            self._active = None
            self._sync_hand(self.machine.hand_pose())
        return iter(())

    # ---- affixment statements

    def _affix_stmt(self, s: ast.Affix, cx: ProcessContext) -> Iterator[None]:
        child = self._frame_variable(s.frame, cx)
        parent = self._frame_variable(s.parent, cx)
        relation = None
        if s.at is not None:
            value = self._eval(s.at, cx)
            if not isinstance(value, Pose):
                raise self._error(s.at, f"AFFIX ... AT needs a trans, not {type_name(value)}")
            relation = value.se3
        with self._refused_at(s):
            affix(child, parent, relation, s.rigid)
        return iter(())

    def _unfix(self, s: ast.Unfix, cx: ProcessContext) -> Iterator[None]:
        a = self._frame_variable(s.frame, cx)
        b = self._frame_variable(s.parent, cx)
        if a.link is not None and a.link.parent is b:
            unlink(a)
        elif b.link is not None and b.link.parent is a:
            unlink(b)
        else:
            raise self._error(s, f"{a.name} is not affixed to {b.name}")
        return iter(())

    def _frame_variable(self, name: ast.Name, cx: ProcessContext) -> Variable:
        variable = cx.scope.lookup(name.name)
        if variable is None:
            self._check_declarable(name.name, name)
            variable = Variable(name.name, "FRAME")
            self._global.variables[name.name] = variable
        if variable.type not in ("FRAME", "TRANS"):
            raise self._error(name, f"{name.name} is a {variable.type.lower()}, not a frame")
        return variable

    @contextlib.contextmanager
    def _refused_at(self, node: ast.Node | None) -> Iterator[None]:
        """A change of the affixment graph that it refuses is an error at ``node``."""
        try:
            yield
        except FrameError as refused:
            raise self._error(node, str(refused)) from None

    def _sync_hand(self, pose: pin.SE3) -> None:
        self._hand.value = Pose(pose, "frame")
        propagate(self._hand, frozenset())


# --------------------------------------------------------------------------------------------
# Dispatch


_Statement = Callable[[Interpreter, Any, ProcessContext], Iterator[None]]

_STATEMENTS: dict[type, _Statement] = {
    ast.Block: Interpreter._block,
    ast.Cobegin: Interpreter._cobegin,
    ast.Declaration: Interpreter._declaration,
    ast.Assign: Interpreter._assign,
    ast.Move: Interpreter._move,
    ast.Open: Interpreter._open,
    ast.Close: Interpreter._close,
    ast.Center: Interpreter._center,
    ast.Affix: Interpreter._affix_stmt,
    ast.Unfix: Interpreter._unfix,
    ast.If: Interpreter._if,
    ast.While: Interpreter._while,
    ast.For: Interpreter._for,
    ast.Signal: Interpreter._signal,
    ast.Wait: Interpreter._wait,
    ast.Abort: Interpreter._abort,
    ast.Stop: Interpreter._stop,
}


def run_program(
    program: ast.Program, machine: Machine, *, hand_names: Sequence[str] = HAND_NAMES
) -> tuple[RunResult, Interpreter]:
    """Run ``program`` on ``machine`` in a fresh interpreter; returns the outcome and it."""
    interpreter = Interpreter(machine, hand_names=hand_names)
    return interpreter.run(program), interpreter
