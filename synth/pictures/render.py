"""A matplotlib figure as the bytes of an SVG or PNG file (the callers write them).

SVG text stays text (``svg.fonttype = none``) so labels can be read back, and the output is
deterministic (fixed hash salt, no date), so a committed picture changes only with its content.
"""

from __future__ import annotations

import io
from typing import Literal

import matplotlib as mpl
from matplotlib.figure import Figure

__all__ = ["Format", "figure_bytes"]

Format = Literal["svg", "png"]


def figure_bytes(fig: Figure, fmt: Format = "svg", dpi: int = 150) -> bytes:
    """The figure as an SVG or PNG file's bytes."""
    buffer = io.BytesIO()
    with mpl.rc_context({"svg.fonttype": "none", "svg.hashsalt": "synth"}):
        metadata = {"Date": None} if fmt == "svg" else {"Software": None}
        fig.savefig(buffer, format=fmt, dpi=dpi, metadata=metadata)
    return buffer.getvalue()
