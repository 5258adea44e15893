"""The Monte Carlo summary, kept as the trials stream past: memory bounded whatever their number.

A :class:`TrialTally` counts outcomes, sums the simulated times [s] for the mean and tracks their
95th percentile; it keeps the first :data:`KEPT_RUNS` runs themselves (tests and reports look at
individual trials) and drops the rest. So a replay of 10⁸ trials holds a few megabytes, not
10⁸ reports.

**The 95th percentile.** Up to :data:`EXACT_TIMES` trials it is exact: numpy's default
(linear interpolation between order statistics, ``np.percentile(times, 95)``). Past that the
stored times are handed to the P² algorithm (R. Jain and I. Chlamtac, "The P² algorithm for
dynamic calculation of quantiles and histograms without storing observations", CACM 28(10),
1985), which keeps five markers — the minimum, the 47.5th, 95th and 97.5th percentiles and the
maximum — and moves each by a piecewise-parabolic step as observations arrive. Its estimate
is not exact, but it is within a fraction of the spread of the times for any smooth
distribution (the test checks a uniform and an exponential one).
"""

from __future__ import annotations

from array import array
from collections import Counter

import numpy as np

from synth.replay.report import OUTCOMES, MonteCarloReport, RunReport

__all__ = ["EXACT_TIMES", "KEPT_RUNS", "P2Quantile", "TrialTally"]

KEPT_RUNS = 10_000
"""Runs a tally keeps (the first ones, in trial order); later ones are counted, not kept."""
EXACT_TIMES = 100_000
"""Trials whose times are stored [8 byte each] for an exact percentile before P² takes over."""


class P2Quantile:
    """The P² estimate of the ``p``-quantile of a stream, from five markers (see the module).

    Start it with :meth:`from_sorted` on at least five observations, then :meth:`add` more.
    """

    def __init__(self, p: float, heights: list[float], positions: list[int], count: int) -> None:
        self.p = p
        self.q = heights  # marker heights
        self.n = positions  # marker positions [1-based ranks]
        self.count = count
        self.increments = (0.0, p / 2.0, p, (1.0 + p) / 2.0, 1.0)
        self.desired = [1.0 + (count - 1) * d for d in self.increments]

    @classmethod
    def from_sorted(cls, p: float, values: np.ndarray) -> P2Quantile:
        """Markers at the order statistics nearest the desired ranks of ``values`` (sorted)."""
        count = len(values)
        if count < 5:
            raise ValueError("P² needs at least five observations to start")
        ranks = [1 + round((count - 1) * d) for d in (0.0, p / 2.0, p, (1.0 + p) / 2.0, 1.0)]
        for i in range(1, 5):  # strictly increasing ranks
            ranks[i] = max(ranks[i], ranks[i - 1] + 1)
        for i in range(3, -1, -1):
            ranks[i] = min(ranks[i], ranks[i + 1] - 1)
        return cls(p, [float(values[r - 1]) for r in ranks], ranks, count)

    def add(self, x: float) -> None:
        """Take one more observation."""
        q, n = self.q, self.n
        if x < q[0]:
            q[0] = x
            k = 0
        elif x >= q[4]:
            q[4] = x
            k = 3
        else:
            k = next(i for i in range(4) if q[i] <= x < q[i + 1])
        for i in range(k + 1, 5):
            n[i] += 1
        for i in range(5):
            self.desired[i] += self.increments[i]
        self.count += 1
        for i in (1, 2, 3):
            d = self.desired[i] - n[i]
            if (d >= 1 and n[i + 1] - n[i] > 1) or (d <= -1 and n[i - 1] - n[i] < -1):
                step = 1 if d > 0 else -1
                candidate = self._parabolic(i, step)
                if not q[i - 1] < candidate < q[i + 1]:
                    candidate = q[i] + step * (q[i + step] - q[i]) / (n[i + step] - n[i])
                q[i] = candidate
                n[i] += step

    def _parabolic(self, i: int, d: int) -> float:
        q, n = self.q, self.n
        return q[i] + d / (n[i + 1] - n[i - 1]) * (
            (n[i] - n[i - 1] + d) * (q[i + 1] - q[i]) / (n[i + 1] - n[i])
            + (n[i + 1] - n[i] - d) * (q[i] - q[i - 1]) / (n[i] - n[i - 1])
        )

    @property
    def value(self) -> float:
        """The current estimate (the middle marker's height)."""
        return self.q[2]


class TrialTally:
    """Outcome counts, time mean and 95th percentile [s] of runs added one at a time.

    ``kept_runs`` and ``exact_times`` override :data:`KEPT_RUNS` and :data:`EXACT_TIMES`.
    """

    def __init__(self, *, kept_runs: int = KEPT_RUNS, exact_times: int = EXACT_TIMES) -> None:
        self.count = 0
        self.counts: Counter[str] = Counter()
        self.runs: list[RunReport] = []
        self.kept_runs = kept_runs
        self.exact_times = max(5, exact_times)
        self._sum = 0.0  # [s]
        self._times: array[float] | None = array("d")
        self._p95: P2Quantile | None = None

    def add(self, run: RunReport) -> None:
        """Count one run (and keep it while fewer than ``kept_runs`` are kept)."""
        self.count += 1
        self.counts[run.outcome] += 1
        self._sum += run.time
        if len(self.runs) < self.kept_runs:
            self.runs.append(run)
        if self._p95 is not None:
            self._p95.add(run.time)
            return
        assert self._times is not None
        self._times.append(run.time)
        if len(self._times) > self.exact_times:
            ordered = np.sort(np.frombuffer(self._times, dtype=np.float64))
            self._p95 = P2Quantile.from_sorted(0.95, ordered)
            self._times = None

    @property
    def successes(self) -> int:
        """Runs that succeeded."""
        return self.counts["success"]

    def p95(self) -> float | None:
        """[s] 95th percentile of the times (exact up to ``exact_times`` runs; None if none)."""
        if self._p95 is not None:
            return self._p95.value
        if not self._times:
            return None
        return float(np.percentile(np.frombuffer(self._times, dtype=np.float64), 95))

    def report(self, seed: int) -> MonteCarloReport:
        """The :class:`MonteCarloReport` of the runs so far (outcomes in :data:`OUTCOMES` order)."""
        outcomes: dict[str, int] = {o: self.counts[o] for o in OUTCOMES if self.counts[o]}
        if not self.count:
            return MonteCarloReport(0, seed, outcomes)
        mean = self._sum / self.count
        p95 = self.p95()
        assert p95 is not None
        return MonteCarloReport(self.count, seed, outcomes, mean, p95)
