"""The proof of a program: its nominal replay, then a sequential Monte Carlo test.

A program is *proven* for a task when

1. its nominal run (the true world equal to the program's beliefs) succeeds, and
2. its success rate over ``trials`` sampled true worlds is at least ``min_success``.

**What is compared.** The observed success *rate* k/n over the full budget of n = ``trials``
trials is compared with ``min_success``: a fixed-size test that allows
``floor((1 − min_success)·n + 1e-9)`` failures. The test stops as soon as its verdict is
decided, which leaves that verdict unchanged:

* *curtailed failure*: the failures already exceed the allowance, so no later trial can save
  the program (at the default 0.99 over 100 trials: the second failure ends the proof);
* *early failure on the Wilson bound*: after at least :data:`MIN_TRIALS_FOR_BOUND` trials the
  95% Wilson upper bound of the rate is below ``min_success``: the program is clearly worse
  than required (this can reject a program that would have scraped through the full budget;
  it never accepts one);
* *early success on the Wilson bound*: the 95% Wilson lower bound is at or above
  ``min_success`` (with 0.99 this needs 381 straight successes, so it only shortens large
  proofs).

**Confirmation.** A program that reaches the budget with failures inside the allowance has
passed on the thinnest evidence the rule accepts: at 0.99 over 100 trials, one failure passes a
program whose true failure rate may be several per cent (a 3.5% one passes 13% of the time:
0.965¹⁰⁰ + 100·0.035·0.965⁹⁹). Such a pass is *confirmed* by a second budget of trials (indices
n … 2n−1 of the same seed): it stands when the failures over all 2n stay within the allowance
of 2n (at the default, two of 200), decided by the same three rules. Acceptance is strictly
harder than the one-stage test's (a program must pass both stages), so a confirmation can only
reject what the one stage would have let through; the 3.5% program now passes 4%
(0.965¹⁰⁰ + 100·0.035·0.965⁹⁹·P[≤ 1 of 100]), a 0.5% one still 88%. A clean budget needs none.
The point is the planner's own error model: a pin that misses its hole once in 100 sampled
worlds means a search pattern with gaps (Δr_ok wider than the capture), which the extension
usually shows (benchmarks/variants.py --seed 11: variants proven 99/100 replayed 193–198/200
afresh).

The verdict is reproducible: the trials are consumed in trial order
(:func:`~synth.replay.trials.iter_trials`) and each is a function of (program, task, seed,
index), so the prefix the rule decides on is the same for any number of workers.

A failed proof carries the replay's reason: the outcome kind, the AL line, the message (which
names the bodies of a collision) and the error parameters sampled in the first failing trial.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from synth.models.spec import TaskSpec
from synth.models.uncertainty import Distribution
from synth.replay.machine import ReplayOptions
from synth.replay.report import MonteCarloReport, RunReport, wilson_interval
from synth.replay.run import replay_context, run_nominal, summarise, trial_errors
from synth.replay.tally import TrialTally
from synth.replay.trials import TrialPool, deferred_interrupts, iter_trials, job_for

__all__ = [
    "DEFAULT_MIN_SUCCESS",
    "DEFAULT_PROOF_TRIALS",
    "MIN_TRIALS_FOR_BOUND",
    "FailedTrial",
    "Proof",
    "ProofOptions",
    "prove",
]

DEFAULT_PROOF_TRIALS = 100
"""Monte Carlo trials of a proof by default: on seed_4_8 they take about 3 s on 2 cores
(benchmarks/proof.py), so ``synth plan`` stays interactive, and at 0.99 they allow one failure."""
DEFAULT_MIN_SUCCESS = 0.99
"""Required success rate by default."""
MIN_TRIALS_FOR_BOUND = 20
"""The Wilson upper bound may end a proof early only after this many trials."""
Z_95 = 1.959963984540054
"""Φ⁻¹(0.975): the two-sided 95% Wilson interval."""

Decision = Literal[
    "nominal", "budget", "confirmed", "curtailed", "wilson-upper", "wilson-lower", "nominal-only"
]
PASSING: frozenset[Decision] = frozenset({"budget", "confirmed", "wilson-lower", "nominal-only"})
"""The decisions that pass a program."""
Progress = Callable[[int, int], None]


@dataclass(frozen=True)
class ProofOptions:
    """How a program is proven.

    ``trials``: Monte Carlo budget (0: the nominal run only); ``min_success``: required rate
    [1]; ``seed``: seed of the trials; ``workers``: processes (None: one per CPU core);
    ``distribution`` overrides every error block's sampling (seed ch. IX).
    """

    trials: int = DEFAULT_PROOF_TRIALS
    min_success: float = DEFAULT_MIN_SUCCESS
    seed: int = 0
    workers: int | None = 1
    distribution: Distribution | None = None

    def __post_init__(self) -> None:
        if self.trials < 0:
            raise ValueError(f"proof trials must be ≥ 0, got {self.trials}")
        if not 0.0 <= self.min_success <= 1.0:
            raise ValueError(f"min_success must lie in [0, 1], got {self.min_success}")

    @classmethod
    def for_task(
        cls,
        spec: TaskSpec,
        *,
        trials: int | None = None,
        min_success: float | None = None,
        seed: int = 0,
        workers: int | None = 1,
        distribution: Distribution | None = None,
    ) -> ProofOptions:
        """Options for ``spec``, each field as given, else the task's, else the default.

        ``trials`` and ``min_success`` fall back on the task's ``proof`` section, then on
        :data:`DEFAULT_PROOF_TRIALS` and :data:`DEFAULT_MIN_SUCCESS`.
        """
        section = spec.proof
        if trials is None:
            trials = section.trials if section is not None else None
        if min_success is None:
            min_success = section.min_success if section is not None else None
        return cls(
            trials=DEFAULT_PROOF_TRIALS if trials is None else trials,
            min_success=DEFAULT_MIN_SUCCESS if min_success is None else min_success,
            seed=seed,
            workers=workers,
            distribution=distribution,
        )

    @property
    def allowed_failures(self) -> int:
        """Failures the full budget tolerates: ⌊(1 − min_success)·trials⌋."""
        return self.allowance(self.trials)

    def allowance(self, trials: int) -> int:
        """Failures ``trials`` trials tolerate: ⌊(1 − min_success)·trials⌋."""
        return math.floor((1.0 - self.min_success) * trials + 1e-9)


@dataclass(frozen=True)
class FailedTrial:
    """The first trial that failed: its index, outcome, AL line, message and sampled errors.

    ``errors`` maps each perturbed frame to its sampled error parameters [m, rad].
    """

    index: int
    outcome: str
    line: int | None
    message: str
    errors: Mapping[str, Mapping[str, float]] = field(default_factory=dict)
    unmet: str | None = None
    """The first pin whose goal is not met (:attr:`~synth.replay.report.RunReport.unmet`)."""

    def describe(self) -> str:
        """``trial 7: abort at AL line 31: ... (sampled box x=+0.61 cm, rz=−4.2°)``."""
        where = f" at AL line {self.line}" if self.line is not None else ""
        parts = []
        for frame, values in self.errors.items():
            shown = ", ".join(
                f"{k}={100 * v:+.2f} cm" if k in ("x", "y", "z") else f"{k}={math.degrees(v):+.2f}°"
                for k, v in values.items()
            )
            parts.append(f"{frame} {shown}")
        sampled = f" (sampled {'; '.join(parts)})" if parts else ""
        return f"trial {self.index}: {self.outcome}{where}: {self.message}{sampled}"

    def to_json(self) -> dict[str, Any]:
        """JSON form (SI units)."""
        return {
            "index": self.index,
            "outcome": self.outcome,
            "line": self.line,
            "message": self.message,
            "errors": {f: dict(v) for f, v in self.errors.items()},
        }


@dataclass(frozen=True)
class Proof:
    """The outcome of proving one program (see the module docstring).

    ``monte_carlo`` summarises the trials the test consumed (≤ the budget in ``options``), as
    a replay of as many trials with the same seed reports them; ``decided_by`` names the rule
    that ended the test.
    """

    options: ProofOptions
    nominal: RunReport
    monte_carlo: MonteCarloReport
    passed: bool
    decided_by: Decision
    first_failure: FailedTrial | None = None

    @property
    def trials(self) -> int:
        """Trials the test consumed."""
        return self.monte_carlo.trials

    @property
    def successes(self) -> int:
        """Trials that succeeded."""
        return self.monte_carlo.successes

    @property
    def outcomes(self) -> Mapping[str, int]:
        """Trials per outcome (only outcomes that occurred)."""
        return self.monte_carlo.outcomes

    @property
    def rate(self) -> float | None:
        """Successes over trials (None without trials)."""
        return self.monte_carlo.success_rate

    @property
    def interval(self) -> tuple[float, float]:
        """The 95% Wilson interval of the success rate."""
        return self.monte_carlo.interval(Z_95)

    @property
    def time_mean(self) -> float:
        """[s] mean simulated program time over the trials (the nominal run's without any)."""
        mean = self.monte_carlo.time_mean
        return self.nominal.time if mean is None else mean

    @property
    def time_p95(self) -> float:
        """[s] 95th percentile of the simulated time (the nominal run's without trials)."""
        p95 = self.monte_carlo.time_p95
        return self.nominal.time if p95 is None else p95

    def reason(self) -> str:
        """Why the proof failed, in one line (empty when it passed)."""
        if self.passed:
            return ""
        n = self.nominal
        if not n.success:
            where = f" at AL line {n.line}" if n.line is not None else ""
            return f"nominal replay failed: {n.outcome}{where}: {n.message}"
        lo, hi = self.interval
        rate = 100 * (self.rate or 0.0)
        head = (
            f"replay proof failed: {self.successes} of {self.trials} trials succeeded "
            f"({rate:.1f}%, Wilson 95% {100 * lo:.1f}–{100 * hi:.1f}%) where "
            f"{100 * self.options.min_success:g}% are required ({self.decided_by})"
        )
        if self.first_failure is None:
            return head
        return f"{head}; first failure {self.first_failure.describe()}"

    def summary(self) -> str:
        """One line for a plan summary."""
        if self.options.trials == 0:
            verdict = "passed" if self.passed else "FAILED"
            return f"nominal replay {verdict} ({self.nominal.time:.2f} s simulated); no trials"
        lo, hi = self.interval
        verdict = "proven" if self.passed else "NOT proven"
        rate = 100 * (self.rate or 0.0)
        return (
            f"{verdict}: {self.successes} of {self.trials} replayed trials succeeded "
            f"({rate:.1f}%, Wilson 95% {100 * lo:.1f}–{100 * hi:.1f}%; required "
            f"{100 * self.options.min_success:g}%, stopped by {self.decided_by}); "
            f"simulated time mean {self.time_mean:.2f} s, p95 {self.time_p95:.2f} s"
        )

    def as_replay_json(self) -> dict[str, Any]:
        """The proof in the shape of a replay report (:meth:`ReplayReport.to_json`).

        ``monte_carlo`` covers the trials the proof ran (a full replay of as many trials with
        the same seed reports the same figures); ``proof`` adds the proof's own record.
        """
        return {
            "ok": self.nominal.success,
            "nominal": self.nominal.to_json(),
            "monte_carlo": self.monte_carlo.to_json(),
            "proof": self.to_json(),
        }

    def to_json(self) -> dict[str, Any]:
        """JSON form (SI units)."""
        lo, hi = self.interval
        return {
            "passed": self.passed,
            "nominal": self.nominal.to_json(),
            "trials": self.trials,
            "budget": self.options.trials,
            "successes": self.successes,
            "success_rate": self.rate,
            "wilson_95": [lo, hi],
            "min_success": self.options.min_success,
            "seed": self.options.seed,
            "decided_by": self.decided_by,
            "outcomes": dict(self.outcomes),
            "time": {"mean": self.time_mean, "p95": self.time_p95},
            "first_failure": None if self.first_failure is None else self.first_failure.to_json(),
        }


def _decide(options: ProofOptions, successes: int, n: int) -> Decision | None:
    """The rule that decides after ``n`` trials with ``successes``, or None to go on.

    Up to the budget n₀ = ``options.trials`` the allowance is n₀'s; past it (a confirmation:
    the budget was reached with failures, see the module docstring) it is 2n₀'s.
    """
    confirming = n > options.trials
    budget = 2 * options.trials if confirming else options.trials
    failures = n - successes
    if failures > options.allowance(budget):
        return "curtailed"
    lo, hi = wilson_interval(successes, n, Z_95)
    if n >= MIN_TRIALS_FOR_BOUND and hi < options.min_success:
        return "wilson-upper"
    if lo >= options.min_success:
        return "wilson-lower"
    if n >= budget:
        if confirming:
            return "confirmed"
        return "budget" if failures == 0 else None
    return None


def prove(
    program_text: str,
    task: TaskSpec,
    options: ProofOptions | None = None,
    *,
    base_dir: str | Path | None = None,
    replay_options: ReplayOptions | None = None,
    pool: TrialPool | None = None,
    progress: Progress | None = None,
) -> Proof:
    """Prove ``program_text`` on ``task`` (see the module docstring).

    ``pool`` runs the trials (shared between proofs; without one a pool of
    ``options.workers`` is made for this proof). ``progress(done, budget)`` is called after
    each trial. Raises ALSyntaxError or SpecError for a program or task the replay cannot use.
    """
    opts = options or ProofOptions()
    context = replay_context(
        program_text,
        task,
        base_dir=base_dir,
        options=replay_options,
        distribution=opts.distribution,
    )
    nominal = run_nominal(context)
    if not nominal.success:
        return Proof(opts, nominal, summarise([], opts.seed), False, "nominal")
    if opts.trials == 0:
        return Proof(opts, nominal, summarise([], opts.seed), True, "nominal-only")
    job = job_for(program_text, context, base_dir=base_dir, options=replay_options)
    own_pool = pool is None
    active = pool if pool is not None else TrialPool(opts.workers)
    tally = TrialTally(kept_runs=0)  # counts and times only: bounded whatever the budget
    first: tuple[int, RunReport] | None = None
    decision: Decision | None = None
    try:
        with deferred_interrupts() as stop:
            # The budget, then (when it ended with failures) its confirmation: n₀ … 2n₀ − 1.
            for start, stop_at in ((0, opts.trials), (opts.trials, 2 * opts.trials)):
                trials = iter_trials(job, context, opts.seed, stop_at, active, stop, start=start)
                for run in trials:
                    tally.add(run)
                    if first is None and not run.success:
                        first = (tally.count - 1, run)
                    if progress is not None:
                        progress(tally.count, stop_at)
                    decision = _decide(opts, tally.successes, tally.count)
                    if decision is not None:
                        trials.close()
                        break
                if decision is not None:
                    break
    except KeyboardInterrupt:
        active.abort()  # Ctrl-C: the workers stop mid-trial, not after their queue
        raise
    finally:
        if own_pool:
            active.close()
    assert decision is not None
    failed = None
    if first is not None:
        index, run = first
        errors = trial_errors(context, opts.seed, index)
        failed = FailedTrial(index, run.outcome, run.line, run.message, errors, run.unmet)
    return Proof(
        options=opts,
        nominal=nominal,
        monte_carlo=tally.report(opts.seed),  # the counts and times a replay would report
        # At a budget the failures are within its allowance (else "curtailed" had fired).
        passed=decision in PASSING,
        decided_by=decision,
        first_failure=failed,
    )
