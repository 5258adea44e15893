"""Bounded Monte Carlo work: streamed trials, a tally, capped workers."""

from __future__ import annotations

import io
import itertools
import tracemalloc
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

import numpy as np
import pytest

import synth.replay.trials as trials_module
from synth.cli import arguments
from synth.cli.arguments import resolve_workers
from synth.cores import available_cores
from synth.exceptions import SynthError
from synth.replay.report import RunReport
from synth.replay.tally import P2Quantile, TrialTally
from synth.replay.trials import TrialPool, iter_trials, max_in_flight


class _CountingExecutor:
    """Runs each job at once and counts submissions (a stand-in for the process pool)."""

    def __init__(self) -> None:
        self.submitted = 0

    def submit(self, fn: Callable[..., Any], *args: Any) -> Future[Any]:
        self.submitted += 1
        future: Future[Any] = Future()
        future.set_result(fn(*args))
        return future


class _Pool:
    def __init__(self, workers: int) -> None:
        self.workers = workers
        self.pool = _CountingExecutor()

    def executor(self) -> _CountingExecutor:
        return self.pool


def _fake_chunk(job: object, seed: int, start: int, stop: int) -> list[RunReport]:
    return [RunReport("success", "", None, float(i), i) for i in range(start, stop)]


def test_trials_are_streamed_with_at_most_k_workers_chunks_in_flight(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(trials_module, "_run_chunk", _fake_chunk)
    pool = _Pool(workers=2)
    tracemalloc.start()
    try:
        stream = iter_trials(None, None, 0, 100_000_000, pool)  # type: ignore[arg-type]
        first = list(itertools.islice(stream, 10))
        _, peak = tracemalloc.get_traced_memory()
        stream.close()
    finally:
        tracemalloc.stop()
    assert [r.statements for r in first] == list(range(10))  # in trial order
    # 10 trials consumed = 3 chunks of 4; the rest in flight is at most max_in_flight(2) = 6
    assert pool.pool.submitted <= 3 + max_in_flight(2) == 9
    assert peak < 1 << 20  # [byte]; a list of 2.5·10⁷ chunk bounds would take gigabytes


def test_the_last_chunk_stops_at_the_count(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(trials_module, "_run_chunk", _fake_chunk)
    runs = list(iter_trials(None, None, 0, 11, _Pool(workers=2)))  # type: ignore[arg-type]
    assert [r.statements for r in runs] == list(range(11))


def _run(time: float, outcome: str = "success") -> RunReport:
    return RunReport(outcome, "", None, time, 1)  # type: ignore[arg-type]


def test_tally_is_exact_up_to_its_store_and_keeps_the_first_runs() -> None:
    rng = np.random.default_rng(3)
    times = rng.exponential(2.0, 500)
    tally = TrialTally(kept_runs=7)
    for i, t in enumerate(times):
        tally.add(_run(float(t), "abort" if i % 10 == 0 else "success"))
    report = tally.report(seed=5)
    assert (report.trials, report.seed, dict(report.outcomes)) == (
        500,
        5,
        {"success": 450, "abort": 50},
    )
    assert report.time_mean == pytest.approx(times.mean())
    assert report.time_p95 == pytest.approx(np.percentile(times, 95))
    assert [r.time for r in tally.runs] == pytest.approx(times[:7])


@pytest.mark.parametrize(
    ("draw", "exact"),
    [
        (lambda rng, n: rng.uniform(0.0, 1.0, n), 0.95),
        (lambda rng, n: rng.exponential(1.0, n), -np.log(0.05)),  # 2.996
    ],
    ids=["uniform", "exponential"],
)
def test_past_the_store_p2_tracks_the_95th_percentile(draw: Any, exact: float) -> None:
    rng = np.random.default_rng(11)
    times = draw(rng, 50_000)
    tally = TrialTally(kept_runs=0, exact_times=1000)
    for t in times:
        tally.add(_run(float(t)))
    p95 = tally.report(0).time_p95
    assert p95 is not None
    # The sample's own percentile is within ~1 % of the distribution's; P² within 2 %.
    assert abs(p95 - np.percentile(times, 95)) < 0.02 * exact
    assert tally._times is None  # the times are no longer stored


def test_p2_needs_five_observations() -> None:
    with pytest.raises(ValueError, match="five"):
        P2Quantile.from_sorted(0.95, np.arange(4.0))


def test_workers_are_capped_at_the_cores_with_a_message() -> None:
    cores = available_cores()
    note = io.StringIO()
    assert resolve_workers(cores + 62, stream=note) == cores
    assert f"--workers {cores + 62} capped at the {cores} CPU cores" in note.getvalue()
    quiet = io.StringIO()
    assert resolve_workers(1, stream=quiet) == 1 and resolve_workers(None, stream=quiet) == cores
    assert quiet.getvalue() == ""
    with pytest.raises(SynthError, match="1 or more"):
        resolve_workers(0)


def test_a_trial_pool_never_has_more_workers_than_cores(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(trials_module, "available_cores", lambda: 3)
    monkeypatch.setattr(arguments, "available_cores", lambda: 3)
    assert TrialPool(1000).workers == 3 and TrialPool(2).workers == 2
