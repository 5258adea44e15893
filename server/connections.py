"""Connection timeouts: slow and idle clients are dropped, so they cannot hold the server open.

uvicorn closes a keep-alive connection after ``timeout_keep_alive`` of silence, but only once
a response has been sent, and any byte received cancels that timer; a client that connects and
sends nothing, or sends its headers one byte at a time, is held forever. The rules here:

- **headers**: a request's headers must be complete within ``header_timeout`` [s] of the
  connection opening or of the previous response ending; otherwise the connection is closed
  without an answer (:class:`DeadlineH11Protocol`);
- **idle**: a keep-alive connection silent for ``keep_alive_timeout`` [s] is closed (uvicorn);
- **body**: the body must arrive within ``body_timeout`` [s] of the headers, else 408
  (:class:`server.limits.BodyLimitMiddleware`);
- **connections**: at most ``max_connections`` are served at once; a request beyond that is
  answered 503 by uvicorn itself (plain text, before the app).
"""

from __future__ import annotations

import asyncio
from typing import Any

import uvicorn
from uvicorn.protocols.http.h11_impl import H11Protocol

from server.settings import Settings


class DeadlineH11Protocol(H11Protocol):
    """uvicorn's h11 protocol with a deadline on reading each request's headers.

    The deadline is armed when the connection opens and again when a response completes,
    and disarmed when h11 has parsed a whole request head (a new request cycle starts).
    """

    header_timeout: float = 10.0  # [s] (a subclass per configuration sets it)

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._header_deadline: asyncio.TimerHandle | None = None

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        """Open the connection and start the first header deadline."""
        super().connection_made(transport)
        self._arm_header_deadline()

    def connection_lost(self, exc: Exception | None) -> None:
        """Forget the deadline, then let uvicorn clean up."""
        self._disarm_header_deadline()
        super().connection_lost(exc)

    def handle_events(self) -> None:
        """Parse what arrived; a new request cycle means its headers are complete."""
        before = self.cycle
        super().handle_events()
        if self.cycle is not before:
            self._disarm_header_deadline()

    def on_response_complete(self) -> None:
        """The next request's headers get a fresh deadline (before pipelined ones are read)."""
        self._arm_header_deadline()
        super().on_response_complete()

    def _arm_header_deadline(self) -> None:
        self._disarm_header_deadline()
        self._header_deadline = self.loop.call_later(self.header_timeout, self._headers_late)

    def _disarm_header_deadline(self) -> None:
        if self._header_deadline is not None:
            self._header_deadline.cancel()
            self._header_deadline = None

    def _headers_late(self) -> None:
        self._header_deadline = None
        if not self.transport.is_closing():
            self.logger.info("closing a connection whose request headers took too long")
            self.transport.close()


def deadline_protocol(header_timeout: float) -> type[DeadlineH11Protocol]:
    """A :class:`DeadlineH11Protocol` class with ``header_timeout`` [s] (uvicorn takes a class)."""
    return type(
        "DeadlineH11Protocol", (DeadlineH11Protocol,), {"header_timeout": float(header_timeout)}
    )


def uvicorn_config(
    app: Any, settings: Settings, host: str, port: int, **kwargs: Any
) -> uvicorn.Config:
    """The uvicorn configuration of ``synth serve``: the app with the module's timeouts."""
    return uvicorn.Config(
        app,
        host=host,
        port=port,
        http=deadline_protocol(settings.header_timeout),
        timeout_keep_alive=max(1, round(settings.keep_alive_timeout)),
        limit_concurrency=settings.max_connections,
        **kwargs,
    )


__all__ = ["DeadlineH11Protocol", "deadline_protocol", "uvicorn_config"]
