"""The command line's files: reading a program, writing an output, naming a source."""

from __future__ import annotations

import sys
from pathlib import Path

from synth.exceptions import SynthError


def write_output(path: str, data: bytes) -> None:
    """Write an output file (its directory made as needed); a usage error when it cannot.

    ``-`` is standard output, as it is for every path the command line reads or writes (it
    wrote a file named ``-``).
    """
    if path == "-":
        stdout = sys.stdout
        binary = getattr(stdout, "buffer", None)
        if binary is not None:
            stdout.flush()
            binary.write(data)
            binary.flush()
        else:
            stdout.write(data.decode("utf-8"))
        return
    out = Path(path)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_bytes(data)
    except OSError as exc:
        raise SynthError(f"cannot write {out}: {exc.strerror or exc}") from None


def read_program(path: str) -> str:
    """The program file's text (``-``: standard input); a usage error when it cannot be read.

    A byte that is not UTF-8 is reported at its line:column.
    """
    try:
        if path == "-":
            stdin = sys.stdin
            binary = getattr(stdin, "buffer", None)
            raw = binary.read() if binary is not None else stdin.read().encode("utf-8")
        else:
            with open(path, "rb") as f:
                raw = f.read()
    except FileNotFoundError:
        raise SynthError(f"{path}: no such program file") from None
    except OSError as exc:
        raise SynthError(f"{path}: cannot read the program: {exc.strerror or exc}") from None
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        from synth.exceptions import ALSyntaxError

        before = raw[: exc.start].decode("utf-8", "replace")
        line = before.count("\n") + 1
        column = len(before) - (before.rfind("\n") + 1) + 1  # in characters, 1-based
        raise ALSyntaxError(
            line,
            column,
            f"byte 0x{raw[exc.start]:02x} is not UTF-8 text (AL programs are UTF-8)",
            filename=display_name(path),
        ) from None


def display_name(path: str) -> str:
    """How a program's source is named in messages: ``<stdin>`` for ``-``."""
    return "<stdin>" if path == "-" else path
