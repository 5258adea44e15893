"""Fair lanes in front of the worker pool: no client can take every worker or starve another.

Rule: a job holds a *slot* while it runs. There are ``capacity`` slots (one per worker); one
client (keyed by its peer address) holds at most ``per_client`` of them at once, and may have at
most ``queue_per_client`` more jobs waiting (beyond that: :class:`TooManyRequests`, 429). When a
slot frees, it goes to the waiting clients in round-robin order — the client served longest ago
first, skipping clients already at their cap — so a client that floods the queue waits behind
its own jobs, not in front of everyone else's. A job (:mod:`server.jobs`) is queued when it is
submitted (:meth:`Lanes.enqueue`, so the 429 is the submission's answer) and then waits as
long as it takes; a caller that gives a timeout gets :class:`ServiceBusy` (503) after it.

With ``per_client = capacity - 1`` (the default when there are at least two workers) one
client's pathological requests leave a worker for everybody else. Distinct clients can still
fill every slot between them; the queue then serves them in turn.
"""

from __future__ import annotations

import asyncio
from collections import Counter, OrderedDict, deque
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

from server.exceptions import ServiceBusy, TooManyRequests


class Lanes:
    """Slots for ``capacity`` concurrent jobs, shared fairly between clients (module rule)."""

    def __init__(self, capacity: int, per_client: int, queue_per_client: int) -> None:
        if capacity < 1 or per_client < 1 or queue_per_client < 0:
            raise ValueError("need capacity >= 1, per_client >= 1, queue_per_client >= 0")
        self.capacity = capacity
        self.per_client = min(per_client, capacity)
        self.queue_per_client = queue_per_client
        self._running: Counter[str] = Counter()
        self._waiting: OrderedDict[str, deque[asyncio.Future[None]]] = OrderedDict()

    @property
    def running(self) -> int:
        """Slots held."""
        return sum(self._running.values())

    @property
    def waiting(self) -> int:
        """Jobs waiting for a slot."""
        return sum(len(q) for q in self._waiting.values())

    def held_by(self, client: str) -> tuple[int, int]:
        """``(running, waiting)`` jobs of ``client``."""
        return self._running[client], len(self._waiting.get(client, ()))

    def enqueue(self, client: str, *, check: bool = True) -> asyncio.Future[None]:
        """Queue one job of ``client`` now; the future is done when the job holds a slot.

        Raises :class:`TooManyRequests` at once when ``check`` and ``client`` already has
        ``per_client + queue_per_client`` jobs (a job accepted before a restart is queued again
        with ``check=False``). Pass the future to :meth:`slot`, or to :meth:`abandon`.
        """
        running, waiting = self.held_by(client)
        allowed = self.per_client + self.queue_per_client
        if check and running + waiting >= allowed:
            raise TooManyRequests(
                f"this client already has {running} job(s) running and {waiting} waiting; "
                f"the server runs at most {self.per_client} and queues at most "
                f"{self.queue_per_client} more per client",
                running=running,
                waiting=waiting,
            )
        granted: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        self._waiting.setdefault(client, deque()).append(granted)
        self._dispatch()
        return granted

    def abandon(self, client: str, granted: asyncio.Future[None]) -> None:
        """Give up the queued job ``granted`` of ``client`` (its slot too, if it got one)."""
        if granted.done() and not granted.cancelled():  # granted as the wait ended
            self._release(client)
        else:
            granted.cancel()
            self._forget(client, granted)

    @asynccontextmanager
    async def slot(
        self, client: str, timeout: float | None, ticket: asyncio.Future[None] | None = None
    ) -> AsyncIterator[None]:
        """Hold a slot for ``client`` for the body of the ``async with``.

        Waits at most ``timeout`` [s] (None: as long as it takes) for the job queued as
        ``ticket`` (:meth:`enqueue`; default: queue it now). Raises :class:`TooManyRequests`
        at once when ``client`` already has ``per_client + queue_per_client`` jobs,
        :class:`ServiceBusy` on timeout.
        """
        await self._acquire(client, timeout, ticket)
        try:
            yield
        finally:
            self._release(client)

    async def _acquire(
        self, client: str, timeout: float | None, ticket: asyncio.Future[None] | None
    ) -> None:
        granted = ticket if ticket is not None else self.enqueue(client)
        try:
            async with asyncio.timeout(timeout):
                await granted
        except BaseException as exc:
            self.abandon(client, granted)
            if isinstance(exc, TimeoutError):
                raise ServiceBusy(
                    f"no worker became free for this request within {timeout:g} s "
                    f"({self.capacity} workers, {self.waiting} job(s) waiting); retry later"
                ) from None
            raise

    def _forget(self, client: str, granted: asyncio.Future[None]) -> None:
        queue = self._waiting.get(client)
        if queue is not None and granted in queue:
            queue.remove(granted)
            if not queue:
                del self._waiting[client]

    def _release(self, client: str) -> None:
        self._running[client] -= 1
        if self._running[client] <= 0:
            del self._running[client]
        self._dispatch()

    def _dispatch(self) -> None:
        """Give free slots to waiting jobs, round-robin over clients below their cap."""
        while self.running < self.capacity:
            client = next((c for c in self._waiting if self._running[c] < self.per_client), None)
            if client is None:
                return
            queue = self._waiting[client]
            granted = queue.popleft()
            if queue:
                self._waiting.move_to_end(client)  # served: to the back of the round
            else:
                del self._waiting[client]
            if granted.done():  # cancelled while queued
                continue
            granted.set_result(None)
            self._running[client] += 1


__all__ = ["Lanes"]
