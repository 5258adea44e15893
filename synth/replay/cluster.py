"""Monte Carlo trials on a Dask distributed cluster: the same trials, in the same order.

:func:`iter_trials_on` is :func:`~synth.replay.trials.iter_trials` with a
``distributed.Client`` in place of the process pool: chunks of trials are submitted as tasks,
at most a few per worker ahead of the consumer, and their runs are yielded in trial order. Each
worker process builds a program's :class:`~synth.replay.run.ReplayContext` once and keeps it
(the same cache as a pool worker), and a trial's outcome depends only on (program, task, seed,
index), so a cluster gives the report a local run with the same seed gives, for any number of
workers. Closing the iterator (Ctrl-C, an early stop) cancels the tasks not yet consumed.

**A real cluster.** Every worker must import this version of synth (install it, with its
fixtures' meshes and arm files reachable at the same paths, or ship a wheel with
``client.upload_file``), and should run one thread per process (``dask worker ADDRESS
--nthreads 1 --nworkers N``): a worker's replay contexts are not thread-safe, so chunks in one
process run one at a time. Then ``synth replay PROGRAM.al --task TASK.yaml --trials 1000000
--dask tcp://scheduler:8786``, or in Python ``replay(..., client=Client("tcp://…"))``.
``--dask local`` starts a ``LocalCluster`` of ``--workers`` processes on this machine.

Dask is an optional dependency (the ``dask`` extra): nothing here imports it at module import.
"""

from __future__ import annotations

import logging
import signal
import threading
import time
import uuid
from collections import deque
from collections.abc import Generator, Iterator
from contextlib import contextmanager
from typing import Any

from synth.exceptions import SynthError
from synth.replay.report import RunReport
from synth.replay.trials import TrialJob, result_or_interrupt, run_chunk

__all__ = ["dask_client", "iter_trials_on"]

_CHUNK = 8
"""Trials per task: a task round trip costs milliseconds, a trial about 0.1 s."""
_AHEAD = 4
"""Tasks in flight per worker thread."""
_LOCK = threading.Lock()
_LOG = logging.getLogger(__name__)

CONNECT_TIMEOUT_S = 5.0
"""[s] how long ``--dask ADDRESS`` keeps retrying an unreachable scheduler before it gives up."""


_STOP_EVERY_S = 0.2
"""[s] how often a worker's chunk asks the scheduler whether the run was stopped."""


def _run_chunk_serial(
    job: TrialJob, seed: int, start: int, stop: int, stopped: str
) -> list[RunReport]:
    """:func:`~synth.replay.trials.run_chunk`, one at a time in a worker process.

    ``stopped`` names a ``distributed.Event`` the consumer sets when it stops early (Ctrl-C):
    looked at between trials, at most every :data:`_STOP_EVERY_S` (a scheduler round trip,
    ~1 ms), so a running chunk ends one trial after the stop instead of running its trials
    out while the cluster waits to close. Its runs are then partial, and nobody reads them.
    """
    from distributed import Event

    with _LOCK:
        event, runs, asked = Event(stopped), [], time.monotonic()
        for i in range(start, stop):
            runs += run_chunk(job, seed, i, i + 1)
            if time.monotonic() - asked >= _STOP_EVERY_S:
                if event.is_set():
                    break
                asked = time.monotonic()
        return runs


def _threads(client: Any) -> int:
    """Worker threads of the cluster the client is connected to (at least 1)."""
    try:
        return max(1, sum(client.nthreads().values()))
    except Exception:  # a client that cannot say: one task at a time per worker we know of
        return 1


def iter_trials_on(
    client: Any, job: TrialJob, seed: int, count: int, stop: threading.Event | None = None
) -> Generator[RunReport, None, None]:
    """Trials 0 … count−1 of ``job`` run on ``client``'s cluster, yielded in trial order.

    At most ``_AHEAD`` tasks of ``_CHUNK`` trials per worker thread are in flight, so memory
    stays bounded whatever ``count`` is. ``stop``: as for
    :func:`~synth.replay.trials.iter_trials`.
    """
    from distributed import Event

    limit = _AHEAD * _threads(client)
    starts: Iterator[int] = iter(range(0, count, _CHUNK))
    in_flight: deque[Any] = deque()
    stopped = f"synth-trials-stopped-{uuid.uuid4().hex}"
    try:
        while True:
            while len(in_flight) < limit:
                a = next(starts, None)
                if a is None:
                    break
                end = min(a + _CHUNK, count)
                in_flight.append(
                    client.submit(_run_chunk_serial, job, seed, a, end, stopped, pure=False)
                )
            if not in_flight:
                return
            yield from result_or_interrupt(in_flight.popleft(), stop)
    finally:
        if in_flight:
            try:
                Event(stopped, client=client).set()  # the running chunks end after their trial
                client.cancel(list(in_flight))
            except Exception as exc:  # best effort: the chunks left run out (8 trials each)
                _LOG.warning("the Dask tasks left could not be cancelled (%s)", _said(exc))


@contextmanager
def _sigint_ignored_by_children() -> Generator[None, None, None]:
    """SIGINT ignored while the ``LocalCluster``'s worker processes start, then restored.

    A terminal's Ctrl-C goes to the whole process group. The workers inherit the ignored
    disposition (a spawned interpreter keeps an ignored SIGINT ignored), so only this process
    sees the Ctrl-C: it stops the trials and closes the cluster, instead of every worker
    dying on a KeyboardInterrupt with a traceback each, seconds later. Off the main thread
    (the Python API from a thread) signals cannot be set, and nothing changes.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


@contextmanager
def dask_client(address: str, workers: int) -> Generator[Any, None, None]:
    """A ``distributed.Client`` for ``--dask ADDRESS``, closed on exit.

    ``"local"`` starts a ``LocalCluster`` of ``workers`` single-threaded processes (stopped on
    exit); any other address connects to the scheduler there (within 5 s). Raises
    :class:`SynthError` when Dask is not installed or the scheduler cannot be reached.
    """
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise SynthError(
            "--dask needs Dask: pip install 'synth[dask]' (dask[distributed])"
        ) from None
    if address == "local":
        with _sigint_ignored_by_children():
            cluster = LocalCluster(
                n_workers=workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,
                silence_logs=logging.ERROR,  # a stop's cancelled tasks each log a warning
            )
        client = Client(cluster)
        try:
            yield client
        finally:
            _close(client, cluster)
        return

    def malformed(why: object) -> SynthError:
        return SynthError(
            f"--dask {address!r}: not a scheduler address ({why}); write HOST:PORT, "
            "tcp://HOST:PORT, or local"
        )

    if not address.strip():  # Client('') falls back on Dask's configured default
        raise malformed("empty")
    try:
        client = Client(address, timeout=CONNECT_TIMEOUT_S)
    except ValueError as exc:  # distributed's address parser: 'bogus', 'foo://x:1'
        raise malformed(exc) from None
    except (OSError, TimeoutError) as exc:
        raise SynthError(f"--dask {address}: cannot reach the scheduler ({exc})") from None
    try:
        yield client
    finally:
        _close(client)


def _said(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__


def _close(client: Any, cluster: Any = None) -> None:
    """Close the client (and a local cluster), a failure to close a warning only.

    The trials' results are in by then: a scheduler or worker slow to stop on a loaded
    machine (a close that times out after a Ctrl-C) must not turn a finished or interrupted
    replay into an internal error.
    """
    for kind, closable in (("client", client), ("local cluster", cluster)):
        if closable is None:
            continue
        try:
            closable.close()
        except Exception as exc:
            _LOG.warning("the Dask %s did not close cleanly (%s)", kind, _said(exc))
