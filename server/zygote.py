"""A warmed-up interpreter that forks the server's worker processes.

A fresh worker interpreter spends about 1 s (``benchmarks/workers.py``, 2-core machine) importing
numpy, scipy, Pinocchio, Coal and synth before it can take a job, and the pool pays that again
for every worker it replaces after an overrun, a cancellation, a crash or a ``MemoryError``. The
zygote pays it once: ``python -m server.zygote FD WARMUP`` imports (``WARMUP``, a
``module:function``), then forks one worker per request. A fork shares the warmed pages and is
ready in about 5 ms.

The zygote is a fresh, single-threaded interpreter (never a fork of the threaded server), so a
fork of it is as safe as ``multiprocessing``'s ``forkserver``, which this follows; unlike the
``forkserver``, it never re-imports the server's ``__main__`` in a worker.

Protocol (a ``SOCK_SEQPACKET`` pair, one message per worker): the server sends the worker's memory
cap [bytes] as ASCII and two descriptors, the worker's end of its job socket and the write end of
a status pipe. The zygote forks, writes the worker's pid to the status pipe (8 bytes), and writes
its exit code (8 bytes, :func:`os.waitstatus_to_exitcode`: negative for a signal) when it reaps
it. :class:`ForkedProcess` reads that pipe, so the server can poll, wait for and kill a process
that is its grandchild. When the server's end closes (the server stopped or was killed), the
zygote kills its workers and exits; a worker whose zygote dies is killed by the kernel
(``PR_SET_PDEATHSIG``, set in the worker).
"""

from __future__ import annotations

import atexit
import contextlib
import importlib
import os
import select
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
import traceback

_WORD = struct.Struct("q")
_NEVER_RAN = -signal.SIGKILL  # the exit code of a worker the zygote never reported


class ForkedProcess:
    """A worker forked by the zygote, with :class:`subprocess.Popen`'s ``pid`` and ``poll``.

    ``wait`` and ``kill`` as well, all read from the status pipe the zygote writes.
    """

    def __init__(self, status_fd: int) -> None:
        self._fd: int | None = status_fd
        self._read_so_far = b""
        self.pid: int | None = None
        self.returncode: int | None = None

    def _read(self, timeout: float | None) -> None:
        """Take what the zygote wrote, waiting up to ``timeout`` [s] (None: until the exit)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while self._fd is not None:
            left = None if deadline is None else max(0.0, deadline - time.monotonic())
            if not select.select([self._fd], [], [], left)[0]:
                return
            chunk = os.read(self._fd, 2 * _WORD.size)
            if not chunk:  # the zygote died without reporting: its workers die with it
                self.returncode = _NEVER_RAN if self.returncode is None else self.returncode
                self.close()
                return
            self._read_so_far += chunk
            if self.pid is None and len(self._read_so_far) >= _WORD.size:
                self.pid = _WORD.unpack_from(self._read_so_far)[0]
            if len(self._read_so_far) >= 2 * _WORD.size:
                self.returncode = _WORD.unpack_from(self._read_so_far, _WORD.size)[0]
                self.close()

    def poll(self) -> int | None:
        """The exit code, or None while the worker runs (or is still being forked)."""
        self._read(0.0)
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        """The exit code, once the worker has exited (:class:`subprocess.TimeoutExpired`)."""
        self._read(timeout)
        if self.returncode is None:
            raise subprocess.TimeoutExpired(f"worker {self.pid}", timeout or 0.0)
        return self.returncode

    def kill(self) -> None:
        """SIGKILL the worker.

        One the zygote has not forked yet is never forked: its job socket is closed by then.
        """
        if self.poll() is None and self.pid is not None and self.pid > 0:
            with contextlib.suppress(ProcessLookupError):
                os.kill(self.pid, signal.SIGKILL)

    def close(self) -> None:
        """Stop reading the status pipe (the exit code stays as last read)."""
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None


class Zygote:
    """The server's side of one zygote process.

    Started on the first :meth:`fork`, and restarted there if it has died.
    """

    def __init__(self, warmup: str) -> None:
        self.warmup = warmup
        self._lock = threading.Lock()
        self._process: subprocess.Popen[bytes] | None = None
        self._control: socket.socket | None = None

    def _start(self) -> socket.socket:
        self.close()
        parent, child = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        with child:
            self._process = subprocess.Popen(
                [sys.executable, "-m", "server.zygote", str(child.fileno()), self.warmup],
                pass_fds=(child.fileno(),),
                stdin=subprocess.DEVNULL,
            )
        self._control = parent
        return parent

    def fork(self, job_fd: int, memory_limit: int) -> ForkedProcess:
        """A worker serving the job socket ``job_fd``, capped at ``memory_limit`` [bytes].

        The caller keeps and closes its copy of ``job_fd``; a cap of 0 is no cap.
        """
        read_end, write_end = os.pipe()
        message = [str(memory_limit).encode()]
        try:
            with self._lock:
                alive = self._process is not None and self._process.poll() is None
                control = self._control if alive and self._control else self._start()
                try:
                    socket.send_fds(control, message, [job_fd, write_end])
                except OSError:  # it died since the poll: once more on a new one
                    socket.send_fds(self._start(), message, [job_fd, write_end])
        finally:
            os.close(write_end)
        return ForkedProcess(read_end)

    def close(self) -> None:
        """Stop the zygote; it kills the workers it forked."""
        if self._control is not None:
            self._control.close()
            self._control = None
        if self._process is not None:
            with contextlib.suppress(subprocess.TimeoutExpired):
                self._process.wait(timeout=2.0)
            if self._process.poll() is None:
                self._process.kill()
                self._process.wait()
            self._process = None


_zygotes: dict[str, Zygote] = {}
_zygotes_lock = threading.Lock()


def zygote_for(warmup: str) -> Zygote:
    """The zygote for ``warmup`` of this process, shared by every pool (stopped at exit)."""
    with _zygotes_lock:
        if warmup not in _zygotes:
            if not _zygotes:
                atexit.register(_close_all)
            _zygotes[warmup] = Zygote(warmup)
        return _zygotes[warmup]


def _close_all() -> None:
    for zygote in _zygotes.values():
        zygote.close()


# -- the zygote process ------------------------------------------------------------------------


def _report(status_fd: int, value: int) -> bool:
    """Write ``value`` to a status pipe; False when its reader is gone."""
    try:
        os.write(status_fd, _WORD.pack(value))
        return True
    except OSError:
        return False


def _serve_one(memory_limit: int, job_fd: int, inherited: list[int]) -> None:
    """In a forked child: become a worker, then leave without the zygote's exit handlers."""
    from multiprocessing.connection import Connection

    from server.workers import _worker_main

    code = 0
    try:
        signal.set_wakeup_fd(-1)
        signal.signal(signal.SIGCHLD, signal.SIG_DFL)
        for fd in inherited:
            with contextlib.suppress(OSError):
                os.close(fd)
        _worker_main(Connection(job_fd), memory_limit)
    except BaseException:
        code = 1
        with contextlib.suppress(BaseException):
            traceback.print_exc()
    finally:
        with contextlib.suppress(BaseException):
            sys.stdout.flush()
            sys.stderr.flush()
        os._exit(code)


def _zygote_main(control_fd: int, warmup: str) -> None:
    """Warm up, then fork a worker per message until the server's end closes."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the server decides when workers stop
    if warmup:
        module, _, name = warmup.partition(":")
        getattr(importlib.import_module(module), name)()
    control = socket.socket(fileno=control_fd)
    wake_read, wake_write = os.pipe()
    os.set_blocking(wake_read, False)
    os.set_blocking(wake_write, False)
    signal.set_wakeup_fd(wake_write)
    signal.signal(signal.SIGCHLD, lambda *_: None)  # wakes the select through the pipe
    status_of: dict[int, int] = {}  # worker pid -> write end of its status pipe

    def reap() -> None:
        while True:
            try:
                pid, status = os.waitpid(-1, os.WNOHANG)
            except ChildProcessError:
                return
            if pid == 0:
                return
            fd = status_of.pop(pid, None)
            if fd is not None:
                _report(fd, os.waitstatus_to_exitcode(status))
                os.close(fd)

    while True:
        readable = select.select([control_fd, wake_read], [], [])[0]
        if wake_read in readable:
            with contextlib.suppress(BlockingIOError):
                os.read(wake_read, 512)
            reap()
        if control_fd not in readable:
            continue
        try:
            message, fds, _, _ = socket.recv_fds(control, 64, 2)
        except OSError:
            message, fds = b"", []
        if not message:
            break
        job_fd, status_fd = fds
        if select.select([job_fd], [], [], 0.0)[0]:  # its server side gave up on it: EOF
            os.close(job_fd)
            os.close(status_fd)
            continue
        pid = os.fork()
        if pid == 0:
            inherited = [control_fd, wake_read, wake_write, status_fd, *status_of.values()]
            _serve_one(int(message), job_fd, inherited)
        os.close(job_fd)
        if _report(status_fd, pid):
            status_of[pid] = status_fd
        else:  # the server gave up on this worker while it was being forked
            os.kill(pid, signal.SIGKILL)
            os.close(status_fd)
            reap()
    for pid in status_of:
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGKILL)
    deadline = time.monotonic() + 5.0
    while status_of and time.monotonic() < deadline:
        reap()
        time.sleep(0.01)


__all__ = ["ForkedProcess", "Zygote", "zygote_for"]


if __name__ == "__main__":  # the zygote: python -m server.zygote FD [module:warmup]
    _zygote_main(int(sys.argv[1]), sys.argv[2] if len(sys.argv) > 2 else "")
