"""The command line's files: reading a program, writing an output, naming a source."""

from __future__ import annotations

import os
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


OUTPUT_OPTIONS = {
    "output": "--output",
    "svg": "--svg",
    "trace": "--trace",
    "export_trajectory": "--export-trajectory",
}
"""The command line's output files: the argument's name and its option."""


INPUT_ARGUMENTS = {"task": "the task file", "program": "the program file"}
"""The command line's input files: the argument's name and how a message calls it."""


def check_outputs(args: object) -> None:
    """:func:`check_writable` of every output the command was given, and none an input.

    ``synth plan task.yaml -o task.yaml`` replaced the task with the program, and ``--trace
    prog.al`` the program just replayed with its trace, without a word (the fourth hunt).
    """
    inputs = {
        name: path
        for name in INPUT_ARGUMENTS
        if isinstance(path := getattr(args, name, None), str) and path != "-"
    }
    for name, option in OUTPUT_OPTIONS.items():
        path = getattr(args, name, None)
        if not isinstance(path, str):
            continue
        check_writable(option, path)
        for kind, given in inputs.items():
            if _same_file(path, given):
                raise SynthError(
                    f"{option} {path}: is {INPUT_ARGUMENTS[kind]}; writing it would destroy it"
                )


def _same_file(a: str, b: str) -> bool:
    """Whether two paths name one existing file (a missing input is its reader's to report)."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def check_writable(option: str, path: str) -> None:
    """A usage error, before any work, when ``path`` could not be written at the end.

    Nothing is made or changed: the file must be a writable file or absent, and its nearest
    existing ancestor a directory this process may write into (:func:`write_output` then makes
    the directories between). A planning run or a Monte Carlo study of minutes then fails in
    a moment, not after its work.
    """
    if path == "-":
        return
    out = Path(path)
    if out.is_dir():
        raise SynthError(f"{option} {path}: is a directory")
    if out.exists():
        if not os.access(out, os.W_OK):
            raise SynthError(f"{option} {path}: cannot write the file (permission denied)")
        return
    ancestor = out.absolute().parent
    while not ancestor.exists():
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise SynthError(f"{option} {path}: {ancestor} is not a directory")
    if not os.access(ancestor, os.W_OK | os.X_OK):
        raise SynthError(f"{option} {path}: cannot write into {ancestor} (permission denied)")


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
