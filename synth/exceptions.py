"""One exception hierarchy for synth: every failure a user can cause is a :class:`SynthError`.

The CLI maps any ``SynthError`` to a one-line message and exit code 2; the server maps it to a
4xx status. Fields are structured so callers never parse messages.
"""

from __future__ import annotations

from typing import Any


class SynthError(Exception):
    """Base class of every error synth raises on purpose."""

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.message = message

    def __str__(self) -> str:
        return self.message


class SpecError(SynthError):
    """A task specification is malformed or inconsistent.

    ``path`` is the dotted field path (``frames[2].uncertainty.x``); ``line`` the 1-based YAML
    line where that field starts, when known.
    """

    def __init__(self, path: str, message: str, line: int | None = None) -> None:
        self.path = path
        self.line = line
        where = path or "<spec>"
        if line is not None:
            where = f"{where} (line {line})"
        super().__init__(f"{where}: {message}")
        self.detail = message


class UnitError(SynthError, ValueError):
    """A quantity has no unit, an unknown unit, or a unit of the wrong dimension.

    Also a ``ValueError`` so that pydantic reports it as a field error with its path.
    """


class FrameLookupError(SynthError):
    """A frame or feature name (or AL name) is not in the task."""

    def __init__(self, name: str, known: list[str]) -> None:
        self.name = name
        self.known = known
        shown = ", ".join(sorted(known)[:20])
        super().__init__(f"unknown frame or feature {name!r}; known: {shown}")


class EstimationError(SynthError):
    """An error bound could not be computed (e.g. the LP solver failed)."""


class ALSyntaxError(SynthError):
    """AL text does not parse.

    ``line`` and ``column`` (1-based) locate the offending token or character; ``context`` is
    that source line with a caret under it (lark's ``get_context``); ``expected`` describes what
    the grammar would accept there (``"THEN"``, ``"';'"``, ``"an expression"``); ``hint``
    names a common mistake when one is recognised (``"AL has no ';' before ELSE"``). The
    message is one line: ``file:line:column: problem (hint); expected one of: ...``.
    """

    def __init__(
        self,
        line: int,
        column: int,
        problem: str,
        *,
        context: str = "",
        expected: tuple[str, ...] = (),
        filename: str = "<al>",
        hint: str | None = None,
    ) -> None:
        self.line = line
        self.column = column
        self.problem = problem
        self.context = context
        self.expected = expected
        self.filename = filename
        self.hint = hint
        text = f"{filename}:{line}:{column}: {problem}"
        if hint:
            text += f" ({hint})"
        if expected:
            if len(expected) == 1:
                text += f"; expected {expected[0]}"
            else:
                text += f"; expected one of: {', '.join(expected)}"
        super().__init__(text)


class ArmModelError(SynthError):
    """An arm model or collision scene cannot be built.

    Raised for an unreadable URDF or parameter file, an unknown tool frame, joint types the arm
    layer does not handle, a joint-limit override of the wrong length, or clashing geometry
    names. ``source`` names the file or spec field at fault (empty when not applicable);
    ``field``, for a fault of an arm file, the ``manipulator.arm`` field it belongs to
    (``tool_frame``, ``fingers``; empty: the file's own).
    """

    def __init__(self, message: str, source: str = "", *, field: str = "") -> None:
        self.source = source
        self.field = field
        super().__init__(f"{source}: {message}" if source else message)


class UnreachableError(SynthError):
    """No attainable arm solution reaches a hand pose.

    ``translation`` [m] and ``rotation`` (row-major 3×3) give the requested pose of the hand in
    the world frame; ``reason`` says which constraint failed first (out of reach, joint limit).
    """

    def __init__(
        self,
        translation: tuple[float, float, float],
        rotation: tuple[float, ...],
        reason: str,
    ) -> None:
        self.translation = translation
        self.rotation = rotation
        self.reason = reason
        x, y, z = (100.0 * v for v in translation)
        super().__init__(f"hand pose at ({x:.2f}, {y:.2f}, {z:.2f}) cm is unreachable: {reason}")


class NoSolutionFound(SynthError):
    """A numerical inverse-kinematics problem has no solution within its options.

    ``problem`` is the problem as built (target, options, limits); ``result`` the best attempt
    (its residual tells how close the solver came). Unlike :class:`UnreachableError` this does
    not prove the pose unreachable: the solver may have missed a solution.
    """

    def __init__(self, problem: object, result: object, message: str) -> None:
        self.problem = problem
        self.result = result
        super().__init__(message)


class TrajectoryError(SynthError):
    """A time-optimal trajectory could not be computed (limits violated or solver failure)."""


class ALRuntimeError(SynthError):
    """An AL program fails while it runs.

    Raised for a type or dimension error, an unknown or unassigned name, a motion of a frame
    that is not affixed to the hand, an affixment cycle, a deadlock, a runaway loop.
    ``line`` and ``column`` (1-based) locate the AL construct at fault; ``problem`` says what
    went wrong; ``filename`` names the program. The message is one line:
    ``file:line:column: problem``. An ``ABORT`` statement is not an error: the interpreter
    reports it as an outcome (:class:`synth.al.interpreter.ALAbort`).
    """

    def __init__(self, line: int, column: int, problem: str, *, filename: str = "<al>") -> None:
        self.line = line
        self.column = column
        self.problem = problem
        self.filename = filename
        super().__init__(f"{filename}:{line}:{column}: {problem}")


class CodegenError(SynthError):
    """A strategy record cannot be written as a program.

    ``field`` names the record field at fault (``pin``, ``pickup.grasp_point.base``,
    ``tap``); ``problem`` says what is wrong with it (a name that is not a valid AL identifier,
    a motion that would have to be split across a stop-on-force clause, a non-finite number).
    The message is one line: ``field: problem``.
    """

    def __init__(self, field: str, problem: str) -> None:
        self.field = field
        self.problem = problem
        super().__init__(f"{field}: {problem}")


class NoStrategyError(SynthError):
    """The planner found no feasible (or no proven) strategy: every candidate was rejected.

    ``rejections`` lists the :class:`~synth.strategies.records.Rejection` records in the order
    the planner made them (grasp generation, approach, refinement, proof); ``root`` is their
    :class:`~synth.strategies.causes.RootCause`. The message's first line names the root cause;
    the per-candidate reasons follow, one per line (ω discarded by the seed's rating folded
    into one line, with the ``--try-harder`` hint only where more ω could help).
    """

    def __init__(self, task: str, rejections: tuple[Any, ...], root: Any) -> None:
        self.task = task
        self.rejections = rejections
        self.root = root
        self.reasons = tuple((r.candidate, r.reason) for r in rejections)
        lines = [f"no proven pin-in-hole strategy for task {task!r}: {root.sentence()}"]
        pruned = [r for r in rejections if r.kind == "pruned"]
        for r in rejections:
            if r.kind != "pruned":
                lines.append(f"  - {r.candidate} [{r.stage or '?'}, {r.kind}]: {r.reason}")
        if pruned:
            hint = (
                " (--try-harder keeps them)"
                if root.helped_by_trying_harder
                else " (keeping them would not help: the root cause is not the arm's pose)"
            )
            lines.append(
                f"  - {len(pruned)} grasp orientations ω discarded by the seed's rating "
                f"(L2122){hint}"
            )
        if not rejections:
            lines.append("  - no candidate strategy was generated")
        super().__init__("\n".join(lines))
