"""The ``synth`` command line's exit codes, defaults and argument types.

Light on purpose: :mod:`synth.cli` imports it to build the parser, and ``synth --help``
stays fast.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from typing import Any, Literal, TextIO

from synth.cores import available_cores
from synth.exceptions import SynthError
from synth.seeds import MAX_SEED

EXIT_OK = 0
EXIT_REPLAY_FAILED = 1
EXIT_USAGE = 2
EXIT_INTERNAL = 70
EXIT_INTERRUPTED = 130
EXIT_BROKEN_PIPE = 141  # 128 + SIGPIPE, as a shell reports a process the signal ended

EXIT_CODES_HELP = f"""exit codes:
  {EXIT_OK}   success
  {EXIT_REPLAY_FAILED}   synth replay: the program's nominal run failed (abort, violation, pin
      not seated)
  {EXIT_USAGE}   unusable input or a refusal: bad arguments, an invalid task or program, no
      strategy proven (synth plan), an AL runtime error (synth replay), an output
      file that could not be written (checked before any work)
  {EXIT_INTERNAL}  internal error (SYNTH_DEBUG=1 prints the traceback)
  {EXIT_INTERRUPTED} interrupted
  {EXIT_BROKEN_PIPE} the reader of standard output closed it (e.g. `| head`)"""
DEFAULT_PROOF_TRIALS = 100
"""Proof trials of ``synth plan`` (kept equal to :data:`synth.replay.proof.DEFAULT_PROOF_TRIALS`
by a test; the CLI does not import the replay to print its help)."""
DEFAULT_MIN_SUCCESS = 0.99
"""Required proof success rate (as :data:`synth.replay.proof.DEFAULT_MIN_SUCCESS`)."""

DEFAULT_TRIALS = 100
"""Monte Carlo trials of ``synth replay`` when ``--trials`` is not given."""

Command = Callable[[argparse.Namespace], int]


def add_workers_argument(parser: Any, what: str) -> None:
    """``--workers K``: the processes running ``what`` (``synth plan`` and ``synth replay``)."""
    parser.add_argument(
        "--workers",
        type=int,
        default=None,
        help=f"processes running {what} (default and most: one per CPU core)",
    )


def resolve_workers(value: int | None, *, stream: TextIO | None = None) -> int:
    """``--workers`` as a count: one per CPU core when not given, and never more than the cores.

    Below 1 is a usage error. A larger count is capped at :func:`available_cores` with a
    one-line note on ``stream`` (standard error by default): more processes than cores only
    add start-up time and memory, and the trials' results do not depend on the count.
    """
    cores = available_cores()
    workers = value if value is not None else cores
    if workers < 1:
        raise SynthError(f"--workers must be 1 or more, got {workers}")
    if workers > cores:
        print(
            f"synth: --workers {workers} capped at the {cores} CPU cores available",
            file=stream if stream is not None else sys.stderr,
        )
        workers = cores
    return workers


def picture_format(path: str) -> Literal["svg", "png"]:
    """The format a picture's file name asks for; a usage error unless ``.svg`` or ``.png``."""
    if path == "-":
        raise SynthError(
            "--svg -: the picture's format comes from the file's name (.svg or .png); give a "
            "file name, not standard output"
        )
    lower = path.lower()
    if lower.endswith(".svg"):
        return "svg"
    if lower.endswith(".png"):
        return "png"
    raise SynthError(f"{path}: a picture must end in .svg or .png")


def integer_from_zero(noun: str, most: int | None = None) -> Callable[[str], int]:
    """An argparse type: an integer from 0 to ``most`` (no bound when None), named ``noun``."""
    allowed = "0 or more" if most is None else f"0 to {most}"

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
        if value < 0 or (most is not None and value > most):
            raise argparse.ArgumentTypeError(f"a {noun} is {allowed}, got {value}")
        return value

    return parse


SEED = integer_from_zero("seed", MAX_SEED)
"""``--seed``: 0 to :data:`~synth.replay.run.MAX_SEED`, the service's range too."""
PORT = integer_from_zero("port", 65535)
"""``--port``: a TCP port, 0 (any free one) to 65535."""
COUNT = integer_from_zero("count")
"""``--trials``, ``--proof-trials``, ``--failures``: how many, 0 (none) or more."""
INDEX = integer_from_zero("trial index")
"""``--trial``: a Monte Carlo trial's index, from 0."""


def rate(text: str) -> float:
    """An argparse type: a success rate, a number from 0 to 1 (``--min-success``)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not 0.0 <= value <= 1.0:  # NaN too
        raise argparse.ArgumentTypeError(f"a success rate is between 0 and 1, got {text}")
    return value
