"""A one-line progress bar of Monte Carlo trials on a text stream, with the rate and the ETA.

The meter is tqdm's (``tqdm.format_meter``): ``proof:  40%|████▊      | 40/100 [00:20<00:30,
2.00trial/s]``. The rate is the trials done over the time since the bar started and the ETA
the trials left at that rate (a sequential proof may stop before its budget, so the ETA is an
upper bound there). The bar keeps its own clock, so tests can pass a fake one.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TextIO

from tqdm import tqdm

__all__ = ["BAR_MIN_TRIALS", "ProgressBar"]

BAR_MIN_TRIALS = 20
"""Fewer trials than this finish too fast to need a bar."""


class ProgressBar:
    """Redraws ``label: pct|bar| done/total [elapsed<left, rate]`` on ``stream``."""

    def __init__(
        self,
        stream: TextIO,
        width: int = 80,
        *,
        label: str = "replay",
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.stream = stream
        self.width = width
        self.label = label
        self.clock = clock
        self.start = clock()
        self.drawn = False
        self._width_drawn = 0

    def line(self, done: int, total: int) -> str:
        """The bar's text for ``done`` of ``total`` trials (without the carriage return)."""
        elapsed = max(self.clock() - self.start, 0.0)
        return tqdm.format_meter(
            min(done, total), total, elapsed, ncols=self.width, prefix=self.label, unit="trial"
        )

    def __call__(self, done: int, total: int) -> None:
        """Redraw for ``done`` of ``total`` trials."""
        text = self.line(done, total)
        pad = max(self._width_drawn - len(text), 0)  # blank what a longer line left behind
        self.stream.write("\r" + text + " " * pad)
        self.stream.flush()
        self._width_drawn = len(text)
        self.drawn = True

    def close(self) -> None:
        """End the bar's line."""
        if self.drawn:
            self.stream.write("\n")
            self.stream.flush()
