"""A matplotlib figure as the bytes of an SVG or PNG file (the callers write them).

SVG text stays text (``svg.fonttype = none``) so labels can be read back, and the output is
deterministic (fixed hash salt, no date), so a committed picture changes only with its content.
"""

from __future__ import annotations

import functools
import io
from collections.abc import Callable
from typing import Literal, ParamSpec

import matplotlib as mpl
from matplotlib.figure import Figure

__all__ = ["Format", "figure_bytes", "literal_text"]

P = ParamSpec("P")

Format = Literal["svg", "png"]


def figure_bytes(fig: Figure, fmt: Format = "svg", dpi: int = 150) -> bytes:
    """The figure as an SVG or PNG file's bytes."""
    buffer = io.BytesIO()
    with mpl.rc_context({"svg.fonttype": "none", "svg.hashsalt": "synth"}):
        metadata = {"Date": None} if fmt == "svg" else {"Software": None}
        fig.savefig(buffer, format=fmt, dpi=dpi, metadata=metadata)
    return buffer.getvalue()


def literal_text(draw: Callable[P, Figure]) -> Callable[P, Figure]:
    """``draw`` with every text it makes shown as written, a ``$`` too.

    Matplotlib reads text between two ``$`` as mathtext: a task named ``$`` backslash ``foo$``
    made every picture of it fail ("Unknown symbol"; a 500 from the service, exit 70 from the
    CLI), and ``cost $5 and $6`` came out garbled. A text's ``parse_math`` is fixed when it is
    made, so the figure is drawn with ``text.parse_math`` off; synth's own labels use none.
    """

    @functools.wraps(draw)
    def drawn(*args: P.args, **kwargs: P.kwargs) -> Figure:
        with mpl.rc_context({"text.parse_math": False}):
            return draw(*args, **kwargs)

    return drawn
