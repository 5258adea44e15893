"""What a replay reports: violations, one run's outcome, the Monte Carlo summary, the whole report.

The JSON shape (SI units) is the one ``synth replay --json`` prints and the HTTP API
returns::

    {"ok": bool,
     "nominal": {"outcome": ..., "message": ..., "line": ..., "time": ..., "statements": ...,
                 "violations": [{"kind": ..., "line": ..., "detail": ...}]},
     "monte_carlo": {"trials": ..., "seed": ..., "success_rate": ..., "outcomes": {...: count},
                     "time": {"mean": ..., "p95": ...}}}

**Outcomes** of a run: ``success`` (the program ran to its end, the pin is seated in the target
hole, the hand has let go of it and is clear, no violation); ``abort`` (the program executed
``ABORT``); ``error`` (the program is faulty: an AL runtime error such as an unknown name);
``violation`` (the arm could not do what the program asked: a target out of reach or beyond a
joint limit, a collision, or a pin wedged in a hole it entered too tilted — the run ends
there); ``failure`` (the program ran to its end but
the pin is not seated, or the hand still holds it or touches it). The issue names the first
three; the other two keep a program that misbehaves apart from one that gives up.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

__all__ = [
    "OUTCOMES",
    "HandDraw",
    "MonteCarloReport",
    "Outcome",
    "ReplayReport",
    "RunReport",
    "Violation",
    "ViolationKind",
    "wilson_interval",
]

ViolationKind = Literal["unreachable", "joint_limit", "collision", "wedged", "too_fast"]
Outcome = Literal["success", "failure", "abort", "violation", "error"]
OUTCOMES: tuple[Outcome, ...] = ("success", "failure", "abort", "violation", "error")


@dataclass(frozen=True)
class Violation:
    """The arm could not do what line ``line`` asked: ``kind``, a one-line ``detail``.

    ``time`` [s] is the machine clock when it happened.
    """

    kind: ViolationKind
    line: int
    detail: str
    time: float = 0.0

    def to_json(self) -> dict[str, Any]:
        """``{"kind", "line", "detail"}``."""
        return {"kind": self.kind, "line": self.line, "detail": self.detail}


@dataclass(frozen=True)
class HandDraw:
    """One hand positioning error a run drew: for target ``target`` of the motion at ``line``.

    ``target`` counts the motion's targets from 1 (its via points, then its destination);
    ``visit`` counts the times the run came to the motion at ``line``, from 1 (a search loop's
    MOVE runs once a point); ``values``: the error's parameters by name (``x``, ``y``, ``z``
    [m], ``rx``, ``ry``, ``rz`` [rad], the task's ``manipulator.hand_error`` block), in the
    order the block lists them.
    """

    line: int | None
    target: int
    values: tuple[tuple[str, float], ...]
    visit: int = 1

    def to_json(self) -> dict[str, Any]:
        """``{"line", "visit", "target", "x", "y", …}`` (SI units)."""
        return {
            "line": self.line,
            "visit": self.visit,
            "target": self.target,
            **dict(self.values),
        }


@dataclass(frozen=True)
class RunReport:
    """One run of the program: its outcome, message, AL line, time [s] and statements executed.

    ``line`` is the AL line of the ABORT, the runtime error or the violation (None otherwise).
    ``unmet`` is the AL name of the first step's pin whose goal is not met, for a ``failure``
    of the task's goal (the run completed; a sequence's planner blames that step).
    ``hand_errors``: the hand's positioning error at each target the run moved to, in order
    (none in the believed world).
    """

    outcome: Outcome
    message: str
    line: int | None
    time: float
    statements: int
    violations: tuple[Violation, ...] = ()
    unmet: str | None = None
    hand_errors: tuple[HandDraw, ...] = ()

    @property
    def success(self) -> bool:
        """True for the ``success`` outcome."""
        return self.outcome == "success"

    def to_json(self) -> dict[str, Any]:
        """The ``nominal`` object of the report's JSON."""
        return {
            "outcome": self.outcome,
            "message": self.message,
            "line": self.line,
            "time": self.time,
            "statements": self.statements,
            "violations": [v.to_json() for v in self.violations],
        }


@functools.lru_cache(maxsize=1 << 16)
def wilson_interval(
    successes: int, trials: int, z: float = 1.959963984540054
) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion (default 95%: z = Φ⁻¹(0.975)).

    scipy's ``binomtest(k, n).proportion_ci(method="wilson")`` at confidence erf(z/√2): centre
    (p̂ + z²/2n)/(1 + z²/n), half-width z·√(p̂(1−p̂)/n + z²/4n²)/(1 + z²/n), p̂ = k/n.
    Kept per (k, n, z): scipy takes 0.4 ms a call, and a sequential proof asks after every
    trial for intervals it has mostly asked before.
    """
    if trials <= 0:
        return (0.0, 1.0)
    from scipy.stats import binomtest  # scipy.stats is slow to import; most runs never ask

    interval = binomtest(successes, trials).proportion_ci(
        confidence_level=math.erf(z / math.sqrt(2.0)), method="wilson"
    )
    return (float(interval.low), float(interval.high))


@dataclass(frozen=True)
class MonteCarloReport:
    """N trials in sampled true worlds: outcome counts and the time [s] statistics.

    ``outcomes`` counts the trials per outcome (only outcomes that occurred); ``time_mean``
    and ``time_p95`` are over all trials (None without trials); ``seed`` seeds the trials.
    """

    trials: int
    seed: int
    outcomes: Mapping[str, int] = field(default_factory=dict)
    time_mean: float | None = None
    time_p95: float | None = None

    @property
    def successes(self) -> int:
        """Trials that succeeded."""
        return int(self.outcomes.get("success", 0))

    @property
    def success_rate(self) -> float | None:
        """Successes over trials (None without trials)."""
        return self.successes / self.trials if self.trials else None

    def interval(self, z: float = 1.959963984540054) -> tuple[float, float]:
        """Wilson interval of the success rate (default 95%)."""
        return wilson_interval(self.successes, self.trials, z)

    def to_json(self) -> dict[str, Any]:
        """The ``monte_carlo`` object of the report's JSON."""
        return {
            "trials": self.trials,
            "seed": self.seed,
            "success_rate": self.success_rate,
            "outcomes": dict(self.outcomes),
            "time": {"mean": self.time_mean, "p95": self.time_p95},
        }


@dataclass(frozen=True)
class ReplayReport:
    """A program replayed on a task: the nominal run and the Monte Carlo trials.

    ``ok`` holds when the nominal run (true world = beliefs) succeeds; ``trials`` keeps the
    runs of the first :data:`~synth.replay.tally.KEPT_RUNS` trials, in trial order (not part
    of the JSON; later trials are counted in ``monte_carlo`` only).
    """

    program: str
    task: str
    nominal: RunReport
    monte_carlo: MonteCarloReport
    trials: tuple[RunReport, ...] = ()
    interrupted: bool = False
    """The trials were stopped (Ctrl-C) after ``monte_carlo.trials`` of ``planned``."""
    planned: int | None = None
    """Trials asked for (None: as many as ``monte_carlo.trials``)."""

    @property
    def ok(self) -> bool:
        """True when the nominal run succeeded."""
        return self.nominal.success

    def to_json(self) -> dict[str, Any]:
        """The report as JSON (SI units)."""
        out: dict[str, Any] = {
            "ok": self.ok,
            "nominal": self.nominal.to_json(),
            "monte_carlo": self.monte_carlo.to_json(),
        }
        if self.interrupted:
            out["interrupted"] = {"done": self.monte_carlo.trials, "planned": self.planned}
        return out
