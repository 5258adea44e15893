"""One exception hierarchy for synth: every failure a user can cause is a :class:`SynthError`.

The CLI maps any ``SynthError`` to a one-line message and exit code 2; the server maps it to a
4xx status. Fields are structured so callers never parse messages.
"""

from __future__ import annotations


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


class UnitError(SynthError):
    """A quantity has no unit, an unknown unit, or a unit of the wrong dimension."""


class FrameLookupError(SynthError):
    """A frame or feature name (or AL name) is not in the task."""

    def __init__(self, name: str, known: list[str]) -> None:
        self.name = name
        self.known = known
        shown = ", ".join(sorted(known)[:20])
        super().__init__(f"unknown frame or feature {name!r}; known: {shown}")


class InfeasibleConstraintsError(SynthError):
    """An uncertainty block's constraints admit no parameter values at all."""


class EstimationError(SynthError):
    """An error bound could not be computed (e.g. the LP solver failed)."""
