"""Worker processes that run planning and replay jobs under a wall-clock budget.

Planning is CPU-bound pure Python/C++ with no way to interrupt it from outside, so a thread
that overruns its budget could only be abandoned, still burning a core. Each job therefore runs
in one of ``size`` long-lived worker processes, forked with synth already imported by this
process's zygote (:mod:`server.zygote`); a job that overruns is answered with
:class:`~server.errors.TimeBudgetExceeded` and its worker is killed and replaced in milliseconds.
The event loop never blocks: it waits on the worker's socket with ``add_reader``.

Why not a library pool: ``concurrent.futures``' ``ProcessPoolExecutor`` cannot stop a running call
— a timed-out or cancelled job would keep its core — and killing one of its processes breaks the
whole executor (``BrokenProcessPool`` for every queued job); ``max_tasks_per_child`` recycles
workers but bounds nothing. pebble's ``ProcessPool`` does stop a task on timeout or cancel by
terminating its worker, and an initializer could set the memory cap, but its workers are
``multiprocessing`` children: forked from the threaded server (unsafe), or spawned/forkserver'd,
which re-imports the server's ``__main__`` in every worker (a BrokenProcessPool in a script without
a ``__main__`` guard); it cannot retire just the worker that hit ``MemoryError``; and it exposes no
per-worker readiness, which ``/healthz`` (``idle``) and the jobs' wait for a worker use. This pool
keeps those semantics in one place: workers forked from a fresh, single-threaded, warmed-up
interpreter (the zygote), a budget that kills exactly the overrunning worker, cancellation that
does the same (``DELETE`` of a running job), the address-space cap, and replacement after a crash
or a ``MemoryError``.

A job is a picklable top-level callable and its arguments. A :class:`~synth.exceptions.SynthError`
raised in a worker is rebuilt in the server as the same class with the same fields, so the one
error handler maps it; any other exception comes back as :class:`~server.errors.WorkerFailed`
(a bug: 500, traceback logged).
"""

from __future__ import annotations

import asyncio
import contextlib
import ctypes
import importlib
import logging
import os
import pickle
import signal
import socket
import subprocess
import sys
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from multiprocessing.connection import Connection
from typing import Any

from server.exceptions import (
    ApiError,
    MemoryBudgetExceeded,
    ServiceBusy,
    TimeBudgetExceeded,
    WorkerFailed,
)
from server.zygote import ForkedProcess, zygote_for
from synth.exceptions import SynthError

log = logging.getLogger("server.workers")

STARTUP_TIMEOUT = 120.0  # [s] a worker's imports and warm-up


def _die_with_parent() -> None:
    """Ask Linux to SIGKILL this process when its parent dies (best effort elsewhere)."""
    if not sys.platform.startswith("linux"):
        return
    with contextlib.suppress(Exception):
        libc = ctypes.CDLL("libc.so.6", use_errno=True)
        libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG


def _pack_synth_error(exc: SynthError) -> tuple[str, str, str, dict[str, Any]]:
    state: dict[str, Any] = {}
    for key, value in vars(exc).items():
        try:
            pickle.dumps(value)
            state[key] = value
        except Exception:
            state[key] = repr(value)
    return type(exc).__module__, type(exc).__qualname__, str(exc), state


def _unpack_synth_error(module: str, qualname: str, message: str, state: dict[str, Any]) -> Any:
    if not module.startswith("synth."):
        return WorkerFailed(f"worker raised an unexpected error type {module}.{qualname}")
    cls: Any = importlib.import_module(module)
    for part in qualname.split("."):
        cls = getattr(cls, part)
    if not (isinstance(cls, type) and issubclass(cls, SynthError)):
        return WorkerFailed(f"worker raised {module}.{qualname}, not a SynthError")
    exc = cls.__new__(cls)
    Exception.__init__(exc, message)
    exc.__dict__.update(state)
    return exc


def _limit_memory(limit: int) -> None:
    """Cap this process's address space at ``limit`` [bytes] (0: no cap), where supported."""
    if limit <= 0:
        return
    with contextlib.suppress(ImportError, ValueError, OSError):
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def _worker_main(conn: Connection, memory_limit: int = 0) -> None:
    """Loop of a worker process: ``(fn, args)`` in, ``("ok", value)`` or an error out."""
    _die_with_parent()
    _limit_memory(memory_limit)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the server decides when workers stop
    conn.send(("ready", os.getpid()))
    while True:
        try:
            message = conn.recv()
        except (EOFError, OSError):
            return
        if message is None:
            return
        fn, args = message
        reply: tuple[Any, ...]
        try:
            reply = ("ok", fn(*args))
        except SynthError as exc:
            reply = ("synth_error", *_pack_synth_error(exc))
        except ApiError as exc:  # e.g. InvalidRequest: picklable as it is
            reply = ("api_error", exc)
        except MemoryError:
            reply = ("memory", traceback.format_exc())
        except BaseException as exc:
            reply = ("bug", f"{type(exc).__name__}: {exc}", traceback.format_exc())
        try:
            conn.send(reply)
        except Exception as exc:  # an unpicklable result is a bug in the job
            conn.send(("bug", f"cannot send the job's result: {exc}", traceback.format_exc()))


@dataclass(eq=False)
class _Worker:
    process: ForkedProcess
    conn: Connection


class WorkerPool:
    """``size`` worker processes; :meth:`run` executes one job on a free one within a budget.

    Workers are forks of this process's zygote for ``warmup`` (a ``module:function`` the zygote
    calls once: its imports), talking over a socket pair; they never re-import the server's
    ``__main__``.
    ``memory_limit`` [bytes] caps each worker's address space (0: no cap), so a job that tries
    to allocate without bound fails in its worker, not the host.
    """

    def __init__(self, size: int, warmup: str = "", memory_limit: int = 0) -> None:
        self.size = size
        self.memory_limit = memory_limit
        self._zygote = zygote_for(warmup)
        self._free: asyncio.Queue[_Worker] = asyncio.Queue()
        self._all: set[_Worker] = set()
        self._tasks: set[asyncio.Task[None]] = set()
        self._closed = False
        self._failed_starts = 0
        self.jobs_run = 0
        self.jobs_killed = 0

    # -- lifecycle ------------------------------------------------------------------------

    async def start(self) -> None:
        """Start the workers; each joins the free queue once its warm-up is done."""
        for _ in range(self.size):
            self._spawn()

    def _spawn(self) -> None:
        if self._closed:
            return
        parent, child = socket.socketpair()
        with child:
            process = self._zygote.fork(child.fileno(), self.memory_limit)
        worker = _Worker(process, Connection(parent.detach()))
        self._all.add(worker)
        task = asyncio.get_running_loop().create_task(self._await_ready(worker))
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    async def _await_ready(self, worker: _Worker) -> None:
        try:
            ready = await self._readable(worker.conn, STARTUP_TIMEOUT)
            message = await asyncio.to_thread(worker.conn.recv) if ready else None
        except (EOFError, OSError):
            message = None
        if isinstance(message, tuple) and message[:1] == ("ready",):
            self._failed_starts = 0
            if self._closed:
                self._stop(worker)
            else:
                self._free.put_nowait(worker)
            return
        self._failed_starts += 1
        delay = min(30.0, 2.0 ** min(self._failed_starts, 5))
        log.error("worker %s failed to start; retrying in %g s", worker.process.pid, delay)
        self._discard(worker)
        await asyncio.sleep(delay)
        self._spawn()

    def stop_replacing(self) -> None:
        """From now on a stopped worker is not replaced (the first step of shutting down).

        Jobs still running keep their workers; cancelling them (``close`` of the job manager)
        then stops those workers without starting new ones.
        """
        self._closed = True

    async def close(self) -> None:
        """Stop every worker (politely, then by force)."""
        self._closed = True
        for task in list(self._tasks):
            task.cancel()
        for worker in list(self._all):
            with contextlib.suppress(Exception):
                worker.conn.send(None)
        deadline = time.monotonic() + 2.0
        for worker in list(self._all):
            with contextlib.suppress(subprocess.TimeoutExpired):
                await asyncio.to_thread(worker.process.wait, max(0.0, deadline - time.monotonic()))
            self._discard(worker)

    def _stop(self, worker: _Worker) -> None:
        with contextlib.suppress(Exception):
            worker.conn.send(None)
        self._discard(worker)

    def _discard(self, worker: _Worker) -> None:
        self._all.discard(worker)
        if worker.process.poll() is None:
            worker.process.kill()
        with contextlib.suppress(subprocess.TimeoutExpired):
            worker.process.wait(timeout=1.0)
        worker.process.close()
        with contextlib.suppress(Exception):
            worker.conn.close()

    def _replace(self, worker: _Worker) -> None:
        self._discard(worker)
        self._spawn()

    # -- state ------------------------------------------------------------------------------

    @property
    def ready(self) -> int:
        """Workers started and idle."""
        return self._free.qsize()

    @property
    def alive(self) -> int:
        """Worker processes running (idle, busy or starting)."""
        return sum(1 for w in self._all if w.process.poll() is None)

    # -- jobs -------------------------------------------------------------------------------

    @staticmethod
    async def _readable(conn: Connection, timeout: float) -> bool:
        """True once ``conn`` has data (or EOF), False after ``timeout`` [s]."""
        loop = asyncio.get_running_loop()
        fired: asyncio.Future[bool] = loop.create_future()
        fd = conn.fileno()

        def wake() -> None:
            if not fired.done():
                fired.set_result(True)

        loop.add_reader(fd, wake)
        try:
            await asyncio.wait_for(fired, timeout)
            return True
        except TimeoutError:
            return False
        finally:
            loop.remove_reader(fd)

    async def _take(self, patience: float) -> _Worker:
        """A free, live worker within ``patience`` [s] (:class:`ServiceBusy`).

        A worker that died while idle (killed from outside, or its zygote with it) is replaced.
        """
        deadline = time.monotonic() + patience
        while True:
            try:
                left = max(0.0, deadline - time.monotonic())
                worker = await asyncio.wait_for(self._free.get(), left)
            except TimeoutError:
                raise ServiceBusy(
                    f"no worker became free within {patience:g} s ({self.size} workers, all "
                    "busy or starting); retry later"
                ) from None
            if worker.process.poll() is None:
                return worker
            log.warning(
                "idle worker %s had exited (%s)", worker.process.pid, worker.process.returncode
            )
            self._replace(worker)

    async def run(
        self,
        fn: Callable[..., Any],
        *args: Any,
        timeout: float,
        what: str,
        wait: float | None = None,
    ) -> Any:
        """``fn(*args)`` in a worker, within ``timeout`` [s].

        With ``wait`` None the budget covers the wait for a free worker plus the job; otherwise
        the job waits at most ``wait`` [s] for a worker and then runs at most ``timeout`` [s].
        ``what`` names the job in messages (``"planning"``). Raises :class:`ServiceBusy` when no
        worker frees up in time, :class:`TimeBudgetExceeded` when the job overruns (its worker is
        killed and replaced), the job's :class:`SynthError`, or :class:`WorkerFailed`. A
        cancelled call kills its worker (and replaces it unless the pool is shutting down).
        """
        patience = timeout if wait is None else wait
        asked = time.monotonic()
        worker = await self._take(patience)
        waited = time.monotonic() - asked
        remaining = timeout if wait is not None else max(0.0, timeout - waited)
        finished = False
        try:
            try:
                worker.conn.send((fn, args))
            except OSError:
                raise WorkerFailed(f"worker died before {what} could start") from None
            if not await self._readable(worker.conn, remaining):
                self.jobs_killed += 1
                raise TimeBudgetExceeded(
                    f"{what} did not finish within the time budget of {timeout:g} s and was "
                    "stopped; simplify the task, ask for fewer trials, or raise the server's "
                    "SYNTH_PLAN_TIMEOUT",
                    budget_seconds=timeout,
                )
            try:
                reply = await asyncio.to_thread(worker.conn.recv)
            except (EOFError, OSError):
                with contextlib.suppress(subprocess.TimeoutExpired):
                    worker.process.wait(timeout=1.0)
                code = worker.process.returncode
                raise WorkerFailed(f"worker died during {what} (exit code {code})") from None
            finished = reply[0] != "memory"  # after a MemoryError, start afresh
        finally:
            if finished:
                self._free.put_nowait(worker)
            else:  # overrun, crash or cancellation: the worker's state is unknown
                self._replace(worker)
        self.jobs_run += 1
        kind = reply[0]
        if kind == "ok":
            return reply[1]
        if kind == "synth_error":
            raise _unpack_synth_error(*reply[1:])
        if kind == "api_error" and isinstance(reply[1], ApiError):
            raise reply[1]
        if kind == "memory":
            log.warning("%s ran out of memory in a worker:\n%s", what, reply[1])
            raise MemoryBudgetExceeded(
                f"{what} needed more memory than a worker may use "
                f"({self.memory_limit / 2**20:.0f} MiB) and was stopped; the task is too large "
                "for this server (e.g. error bounds far larger than the tolerances)",
                limit_mib=round(self.memory_limit / 2**20),
            )
        raise WorkerFailed(f"{what} failed in a worker: {reply[1]}", reply[2])


__all__ = ["WorkerPool"]
