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
