"""Monte Carlo trials in trial order, in this process or in a pool of worker processes.

:func:`iter_trials` yields trial i's :class:`~synth.replay.report.RunReport` for i = 0, 1, …
in that order, whatever order the workers finish in, so a consumer that stops early (the
proof's sequential test, :mod:`synth.replay.proof`) sees the same prefix for any number of
workers: a trial's outcome depends only on (program, task, seed, i) (:func:`run_trial`).
Closing the iterator cancels the trials not yet started.

A :class:`TrialPool` is a process pool (``spawn`` start method) that several replays can
share: each worker builds a program's :class:`~synth.replay.run.ReplayContext` once, keyed by
the program text, the task and the options, and keeps the last few, so proving one candidate
after another pays the workers' start-up (imports, arm model, meshes) once.
"""

from __future__ import annotations

import hashlib
import multiprocessing
import signal
from collections import OrderedDict, deque
from collections.abc import Generator
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from synth.models.spec import TaskSpec
from synth.replay.cli_command import available_cores
from synth.replay.machine import ReplayOptions
from synth.replay.report import RunReport

if TYPE_CHECKING:  # run imports this module
    from synth.replay.run import ReplayContext

__all__ = ["TrialJob", "TrialPool", "iter_trials", "job_for", "max_in_flight", "run_chunk"]

_CHUNK = 4
"""Trials per task sent to a worker: small, so an early stop wastes little."""
_AHEAD = 3
"""Chunks in flight per worker."""
_CACHED_CONTEXTS = 4
"""Replay contexts a worker keeps (one per program proven recently)."""


@dataclass(frozen=True)
class TrialJob:
    """What a worker needs to rebuild a replay context: the program and its task.

    ``spec`` is the caller's context's task (contacts already resolved, a ``--distribution``
    already applied: building a context from it again changes nothing); ``base_dir`` resolves
    URDF paths.
    """

    program_text: str
    spec: TaskSpec
    filename: str = "<al>"
    base_dir: str | None = None
    options: ReplayOptions | None = None

    @property
    def key(self) -> str:
        """A digest of everything that makes the context."""
        digest = hashlib.sha256()
        for part in (
            self.program_text,
            self.spec.model_dump_json(),
            self.filename,
            str(self.base_dir),
            repr(self.options),
        ):
            digest.update(part.encode())
            digest.update(b"\0")
        return digest.hexdigest()


_CONTEXTS: OrderedDict[str, ReplayContext] = OrderedDict()


def _context(job: TrialJob) -> ReplayContext:
    from synth.replay.run import build_context

    key = job.key
    if key in _CONTEXTS:
        _CONTEXTS.move_to_end(key)
        return _CONTEXTS[key]
    context = build_context(
        job.program_text,
        job.spec,
        filename=job.filename,
        base_dir=job.base_dir,
        options=job.options,
    )
    _CONTEXTS[key] = context
    while len(_CONTEXTS) > _CACHED_CONTEXTS:
        _CONTEXTS.popitem(last=False)
    return context


def run_chunk(job: TrialJob, seed: int, start: int, stop: int) -> list[RunReport]:
    """Trials ``start`` … ``stop − 1`` of ``job`` in this process (its context cached)."""
    return _run_chunk(job, seed, start, stop)


def _run_chunk(job: TrialJob, seed: int, start: int, stop: int) -> list[RunReport]:
    from synth.replay.run import run_trial

    context = _context(job)
    return [run_trial(context, seed, i) for i in range(start, stop)]


def _ignore_interrupts() -> None:
    """Worker initializer: Ctrl-C is the parent's to handle (it stops the workers itself)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _import_replay() -> None:
    import synth.replay.run  # noqa: F401  (pinocchio, coal, the AL parser and the machine)


class TrialPool:
    """A pool of ``workers`` processes for Monte Carlo trials, started on first use.

    Use it as a context manager, or call :meth:`close`. ``workers=None`` takes one per CPU
    core, and more than the cores are capped at the cores
    (:func:`~synth.replay.cli_command.available_cores`; the CLI says so when it caps).
    """

    def __init__(self, workers: int | None = None) -> None:
        cores = available_cores()
        self.workers = max(1, min(workers if workers is not None else cores, cores))
        self._executor: ProcessPoolExecutor | None = None

    def executor(self) -> ProcessPoolExecutor:
        """The process pool (started now if it is not yet)."""
        if self._executor is None:
            self._executor = ProcessPoolExecutor(
                max_workers=self.workers,
                mp_context=multiprocessing.get_context("spawn"),
                initializer=_ignore_interrupts,
            )
        return self._executor

    def warm(self) -> None:
        """Start the workers now, each importing the replay.

        The start-up then overlaps whatever the caller does next (the pipeline plans).
        """
        if self.workers > 1:
            executor = self.executor()
            for _ in range(self.workers):
                executor.submit(_import_replay)

    def close(self) -> None:
        """Stop the workers; trials not yet started are cancelled."""
        if self._executor is not None:
            self._executor.shutdown(wait=True, cancel_futures=True)
            self._executor = None

    def abort(self) -> None:
        """Stop now: cancel the queued trials and terminate the workers mid-trial (Ctrl-C)."""
        executor = self._executor
        if executor is None:
            return
        self._executor = None
        processes = list((getattr(executor, "_processes", None) or {}).values())
        executor.shutdown(wait=False, cancel_futures=True)
        for process in processes:
            process.terminate()
        for process in processes:
            process.join(timeout=1.0)

    def __enter__(self) -> TrialPool:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def max_in_flight(workers: int) -> int:
    """Chunks submitted and not yet consumed, at most: ``_AHEAD`` per worker.

    So the futures and pending results of :func:`iter_trials` are O(workers), not O(trials).
    """
    return _AHEAD * workers


def iter_trials(
    job: TrialJob,
    context: ReplayContext,
    seed: int,
    count: int,
    pool: TrialPool | None = None,
) -> Generator[RunReport, None, None]:
    """Trials 0 … count−1 of ``job`` in trial order (see the module docstring).

    The trials are streamed: at most :func:`max_in_flight` chunks of ``_CHUNK`` trials are
    submitted ahead of the consumer, whatever ``count`` is (10⁸ trials start at once and hold
    no more memory than 10).

    ``context`` is the caller's own :class:`~synth.replay.run.ReplayContext` of ``job``: the
    trials run in it when ``pool`` is None or has one worker.
    """
    if pool is None or pool.workers == 1 or count <= _CHUNK:
        from synth.replay.run import run_trial

        for i in range(count):
            yield run_trial(context, seed, i)
        return
    executor = pool.executor()
    starts = iter(range(0, count, _CHUNK))  # lazy: nothing is made per trial up front
    in_flight: deque[Future[list[RunReport]]] = deque()
    try:
        while True:
            while len(in_flight) < max_in_flight(pool.workers):
                a = next(starts, None)
                if a is None:
                    break
                in_flight.append(executor.submit(_run_chunk, job, seed, a, min(a + _CHUNK, count)))
            if not in_flight:
                return
            yield from in_flight.popleft().result()
    finally:
        for future in in_flight:
            future.cancel()


def job_for(
    program_text: str,
    context: ReplayContext,
    *,
    filename: str = "<al>",
    base_dir: str | Path | None = None,
    options: ReplayOptions | None = None,
) -> TrialJob:
    """The :class:`TrialJob` of a replay whose own context is ``context``."""
    return TrialJob(
        program_text, context.spec, filename, None if base_dir is None else str(base_dir), options
    )
