"""Monte Carlo trials in trial order, in this process or in a pool of worker processes.

:func:`iter_trials` yields trial i's :class:`~synth.replay.report.RunReport` for i = 0, 1, …
in that order, whatever order the workers finish in, so a consumer that stops early (the
proof's sequential test, :mod:`synth.replay.proof`) sees the same prefix for any number of
workers: a trial's outcome depends only on (program, task, seed, i) (:func:`run_trial`).
Closing the iterator cancels the trials not yet started.

A :class:`TrialPool` is a process pool (``spawn`` start method, or ``fork`` where spawn would
re-run an unguarded script: :func:`start_method`) that several replays can share: each
worker builds a program's :class:`~synth.replay.run.ReplayContext` once, keyed by the
program text, the task and the options, and keeps the last few, so proving one candidate
after another pays the workers' start-up (imports, arm model, meshes) once.
"""

from __future__ import annotations

import ast as pyast
import hashlib
import multiprocessing
import os
import signal
import sys
import threading
import warnings
from collections import OrderedDict, deque
from collections.abc import Generator, Iterator
from concurrent.futures import Future, ProcessPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from synth.cores import available_cores
from synth.models.spec import TaskSpec
from synth.replay.machine import ReplayOptions
from synth.replay.report import RunReport

if TYPE_CHECKING:  # run imports this module
    from synth.replay.run import ReplayContext

__all__ = [
    "TrialJob",
    "TrialPool",
    "deferred_interrupts",
    "iter_trials",
    "job_for",
    "main_reimport_is_unsafe",
    "max_in_flight",
    "result_or_interrupt",
    "run_chunk",
    "start_method",
]

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
    from synth.replay.run import replay_context

    key = job.key
    if key in _CONTEXTS:
        _CONTEXTS.move_to_end(key)
        return _CONTEXTS[key]
    context = replay_context(
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


def _is_main_guard(node: pyast.AST) -> bool:
    """Whether ``node`` is ``if __name__ == "__main__":`` (either operand order)."""
    if not isinstance(node, pyast.If) or not isinstance(node.test, pyast.Compare):
        return False
    test = node.test
    if len(test.ops) != 1 or not isinstance(test.ops[0], pyast.Eq):
        return False
    sides = [test.left, test.comparators[0]]
    names = {s.id for s in sides if isinstance(s, pyast.Name)}
    strings = {s.value for s in sides if isinstance(s, pyast.Constant)}
    return names == {"__name__"} and strings == {"__main__"}


def _guarded(source: str, line: int) -> bool:
    """Whether ``line`` of a script lies inside an ``if __name__ == "__main__":`` block."""
    try:
        tree = pyast.parse(source)
    except SyntaxError:
        return False
    for node in pyast.walk(tree):
        if _is_main_guard(node):
            assert isinstance(node, pyast.If)
            end = node.end_lineno or node.lineno
            if node.body and node.body[0].lineno <= line <= end:
                return True
    return False


def main_reimport_is_unsafe() -> bool:
    """Whether a ``spawn`` worker would re-run the code that is starting it.

    A spawned worker imports the parent's ``__main__`` again (as ``__mp_main__``, from its
    file or, under ``python -m``, its module name). That is harmless when the code starting
    the pool runs in a function, under an ``if __name__ == "__main__":`` guard, in ``python
    -c`` or at an interactive prompt. It is not when a plain script calls the replay at its
    top level without the guard: each worker would run the script again, start its own pool
    while bootstrapping, and die — the parent sees ``BrokenProcessPool``. This finds that case:
    the main module's top-level frame is on the call stack at a line outside any guard.
    """
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    if not path or not os.path.exists(path):
        return False
    frame = sys._getframe(1)
    while frame is not None:
        code = frame.f_code
        if code.co_name == "<module>" and os.path.exists(code.co_filename):
            try:
                same = os.path.samefile(code.co_filename, path)
            except OSError:
                same = False
            if same:
                try:
                    with open(path, encoding="utf-8") as f:
                        source = f.read()
                except (OSError, UnicodeDecodeError):
                    return True
                return not _guarded(source, frame.f_lineno)
        frame = frame.f_back  # type: ignore[assignment]
    return False


def start_method() -> str | None:
    """The pool's start method: ``spawn``, ``fork``, or None for trials in this process.

    ``spawn`` by default: a fresh interpreter per worker inherits no threads or locks of the
    parent (a server's, HiGHS's), on every platform. When spawn would re-run the calling script
    (:func:`main_reimport_is_unsafe`), ``fork`` on Linux, which copies this process instead of
    importing ``__main__`` again (the pool forks its workers before its own manager thread
    starts, and the replay takes no lock another thread of the parent could hold). ``forkserver``
    would not help: its workers import ``__main__`` as spawn's do. Where fork is not safe
    (macOS, Windows) there is no such way, and the trials run in this process: None, with a
    :class:`RuntimeWarning` from :meth:`TrialPool.executor`'s caller.
    """
    if not main_reimport_is_unsafe():
        return "spawn"
    if sys.platform.startswith("linux") and "fork" in multiprocessing.get_all_start_methods():
        return "fork"
    return None


class TrialPool:
    """A pool of ``workers`` processes for Monte Carlo trials, started on first use.

    Use it as a context manager, or call :meth:`close`. ``workers=None`` takes one per CPU
    core, and more than the cores are capped at the cores
    (:func:`~synth.cores.available_cores`; the CLI says so when it caps).
    The start method is :func:`start_method`'s, decided when the pool is made; when it is
    None (an unguarded script where fork is unsafe) the pool has one worker, this process,
    and says so with a :class:`RuntimeWarning`. :attr:`method` tells which.
    """

    def __init__(self, workers: int | None = None) -> None:
        cores = available_cores()
        self.workers = max(1, min(workers if workers is not None else cores, cores))
        self.method: str | None = "spawn"
        if self.workers > 1:
            self.method = start_method()
            if self.method is None:
                warnings.warn(
                    "synth: trials run in this process: a worker would re-run this script "
                    '(no `if __name__ == "__main__":` guard) and fork is unsafe here',
                    RuntimeWarning,
                    stacklevel=2,
                )
                self.workers = 1
        self._executor: ProcessPoolExecutor | None = None

    def executor(self) -> ProcessPoolExecutor:
        """The process pool (started now if it is not yet)."""
        if self._executor is None:
            self._executor = ProcessPoolExecutor(
                max_workers=self.workers,
                mp_context=multiprocessing.get_context(self.method or "spawn"),
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


@contextmanager
def deferred_interrupts() -> Iterator[threading.Event]:
    """Ctrl-C sets the event yielded instead of raising wherever the main thread is.

    A ``KeyboardInterrupt`` raised asynchronously can land inside the process pool's own
    bookkeeping (a ``with lock:`` of ``ProcessPoolExecutor.submit``, a future's condition) and
    leave a lock held, and then stopping the pool deadlocks: ``synth replay --workers 2``
    was seen to hang after Ctrl-C about once in 20 runs. The trial loops
    (:func:`iter_trials`, :func:`~synth.replay.cluster.iter_trials_on`) raise it themselves
    at a safe point instead, between trials or while waiting for one
    (:func:`result_or_interrupt`), within :data:`_POLL` seconds. Outside the main thread, or
    when SIGINT is not Python's default handler, nothing is installed and the event stays
    clear.
    """
    stop = threading.Event()
    main = threading.current_thread() is threading.main_thread()
    if not main or signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield stop
        return

    def interrupted(signum: int, frame: object) -> None:
        stop.set()

    previous = signal.signal(signal.SIGINT, interrupted)
    try:
        yield stop
    finally:
        signal.signal(signal.SIGINT, previous)


_POLL = 0.05
"""[s] how often a wait for a trial's result looks at the interrupt event."""


def result_or_interrupt(future: Any, stop: threading.Event | None) -> Any:
    """``future.result()``, raising ``KeyboardInterrupt`` once ``stop`` is set.

    For a ``concurrent.futures`` or a Dask future alike (both raise the builtin
    ``TimeoutError`` when a wait times out).
    """
    if stop is None:
        return future.result()
    while True:
        if stop.is_set():
            raise KeyboardInterrupt
        try:
            return future.result(timeout=_POLL)
        except TimeoutError:
            continue


def iter_trials(
    job: TrialJob,
    context: ReplayContext,
    seed: int,
    count: int,
    pool: TrialPool | None = None,
    stop: threading.Event | None = None,
    *,
    start: int = 0,
) -> Generator[RunReport, None, None]:
    """Trials ``start`` … count−1 of ``job`` in trial order (see the module docstring).

    The trials are streamed: at most :func:`max_in_flight` chunks of ``_CHUNK`` trials are
    submitted ahead of the consumer, whatever ``count`` is (10⁸ trials start at once and hold
    no more memory than 10).

    ``context`` is the caller's own :class:`~synth.replay.run.ReplayContext` of ``job``: the
    trials run in it when ``pool`` is None or has one worker. ``stop`` (of
    :func:`deferred_interrupts`): once set, a ``KeyboardInterrupt`` is raised here, between
    trials or while waiting for one.
    """
    if pool is None or pool.workers == 1 or count - start <= _CHUNK:
        from synth.replay.run import run_trial

        for i in range(start, count):
            if stop is not None and stop.is_set():
                raise KeyboardInterrupt
            yield run_trial(context, seed, i)
        return
    executor = pool.executor()
    starts = iter(range(start, count, _CHUNK))  # lazy: nothing is made per trial up front
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
            yield from result_or_interrupt(in_flight.popleft(), stop)
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
