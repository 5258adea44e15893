"""A process's state, shared by the interpreter's parts: scope, handled motion, ``ABORT``.

A process carries its innermost scope and the motion whose monitor handler it runs; ``ABORT``
unwinds the interpreter as an exception.

:mod:`synth.al.interpreter` runs statements, :mod:`synth.al.evaluation` evaluates
expressions and :mod:`synth.al.motion_statements` turns motion statements into the machine's
motions; each passes these records to the others.
"""

from __future__ import annotations

from dataclasses import dataclass

from synth.al.frames import Scope

__all__ = ["ALAbort", "Aborted", "MotionState", "ProcessContext"]


@dataclass(frozen=True)
class ALAbort:
    """The program ended with ``ABORT(...)``: its message and the AL line of the statement."""

    message: str
    line: int
    column: int = 0


class Aborted(Exception):
    """Unwinds the interpreter after ``ABORT``; :meth:`Interpreter.run` catches it."""

    def __init__(self, abort: ALAbort) -> None:
        super().__init__(abort.message)
        self.abort = abort


@dataclass
class MotionState:
    """One motion statement in progress, as its monitor handlers see it."""

    stopped: bool = False
    finished: bool = False


@dataclass(frozen=True)
class ProcessContext:
    """What a process carries: its innermost scope, and the motion whose handler it runs."""

    scope: Scope
    motion: MotionState | None = None
