"""What a native library writes to the process's stderr, captured for a message of synth's.

urdfdom (inside Pinocchio's URDF reader) reports through console_bridge, straight to file
descriptor 2, before Pinocchio raises: a user saw ``Error:   Error=XML_ERROR_PARSING_TEXT …
at line 103 in /project/urdfdom/urdf_parser/src/model.cpp`` above synth's own one-line
message. :func:`captured_stderr` points descriptor 2 at a temporary file for the call, so the
caller can put the useful part in its message (:func:`native_detail`) or, when the call
succeeds, pass the text on unchanged: nothing written meanwhile is lost, another thread's
output included.
"""

from __future__ import annotations

import os
import re
import sys
import tempfile
import threading
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["captured_stderr", "native_detail"]

_LOCK = threading.Lock()
# console_bridge's source position of the message: the library's file, not the user's
_WHERE = re.compile(r"^\s*at line \d+ in \S+$")


class Captured:
    """The text written to descriptor 2 during a :func:`captured_stderr` block."""

    def __init__(self) -> None:
        self.text = ""


@contextmanager
def captured_stderr() -> Iterator[Captured]:
    """Capture descriptor 2 for the block; on a clean exit, write the text back to stderr.

    On an exception the text stays in the returned record for the handler's message. A
    process whose descriptor 2 cannot be duplicated (closed) runs the block uncaptured.
    """
    captured = Captured()
    with _LOCK, tempfile.TemporaryFile(mode="w+b") as sink:
        sys.stderr.flush()
        try:
            saved = os.dup(2)
        except OSError:
            yield captured
            return
        os.dup2(sink.fileno(), 2)
        clean = False
        try:
            yield captured
            clean = True
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            captured.text = sink.read().decode("utf-8", errors="replace")
            if clean and captured.text:
                sys.stderr.write(captured.text)
                sys.stderr.flush()


def native_detail(text: str) -> str:
    """The captured text as one line: its messages, without the library's source positions."""
    lines = [line.strip() for line in text.splitlines()]
    kept = [
        line.removeprefix("Error:").strip() for line in lines if line and not _WHERE.match(line)
    ]
    return "; ".join(line for line in kept if line)
