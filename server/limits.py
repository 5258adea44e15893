"""Request body limits: 413 before a route reads too much, 408 when the body comes too slowly.

A declared ``Content-Length`` over the limit is refused at once; a body without one (chunked)
is read up to the limit and refused as soon as it goes over. Bodies within the limit are
buffered (they are small) and handed to the app unchanged. The whole body must arrive within
``timeout()`` [s] of the request's headers, so a client trickling bytes cannot hold a
connection and a request task open; both refusals close the connection. The limits come from
the settings the routes see, so a test's ``dependency_overrides`` applies here too.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable

from starlette.types import ASGIApp, Message, Receive, Scope, Send

from server.errors import problem_response
from server.exceptions import PayloadTooLarge, RequestTimeout


class BodyLimitMiddleware:
    """Refuse bodies over ``limit()`` bytes (413) or slower than ``timeout()`` [s] (408)."""

    def __init__(
        self,
        app: ASGIApp,
        limit: Callable[[Scope], int],
        timeout: Callable[[Scope], float] | None = None,
    ) -> None:
        self.app = app
        self.limit = limit
        self.timeout = timeout

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Check the body of an HTTP request, then pass the request on."""
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        limit = self.limit(scope)
        declared = dict(scope.get("headers") or ()).get(b"content-length")
        if declared is not None:
            try:
                length = int(declared)
            except ValueError:
                length = -1
            if length > limit:
                await self._refuse(scope, receive, send, limit)
                return
        seconds = self.timeout(scope) if self.timeout is not None else None
        loop = asyncio.get_running_loop()
        deadline = None if seconds is None else loop.time() + seconds  # [s] loop clock
        chunks: list[bytes] = []
        size = 0
        while True:
            try:
                async with asyncio.timeout_at(deadline):
                    message = await receive()
            except TimeoutError:
                assert seconds is not None
                await self._send(
                    scope,
                    receive,
                    send,
                    RequestTimeout(
                        f"the request body did not arrive within {seconds:g} s",
                        timeout_seconds=seconds,
                    ),
                )
                return
            if message["type"] != "http.request":  # client went away
                await self.app(scope, _replay([message], receive), send)
                return
            body = message.get("body", b"")
            size += len(body)
            if size > limit:
                await self._refuse(scope, receive, send, limit)
                return
            chunks.append(body)
            if not message.get("more_body", False):
                break
        whole: Message = {"type": "http.request", "body": b"".join(chunks), "more_body": False}
        await self.app(scope, _replay([whole], receive), send)

    @classmethod
    async def _refuse(cls, scope: Scope, receive: Receive, send: Send, limit: int) -> None:
        refusal = PayloadTooLarge(
            f"the request body is larger than the limit of {limit} bytes", limit_bytes=limit
        )
        await cls._send(scope, receive, send, refusal)

    @staticmethod
    async def _send(scope: Scope, receive: Receive, send: Send, refusal: Exception) -> None:
        """Answer ``refusal`` and close the connection (the rest of the body is unread)."""
        response = problem_response(refusal)
        response.headers["Connection"] = "close"
        await response(scope, receive, send)


def _replay(messages: list[Message], then: Receive) -> Receive:
    """``receive`` that yields ``messages`` first, then whatever the client sends next."""
    queue = list(messages)

    async def receive() -> Message:
        if queue:
            return queue.pop(0)
        return await then()

    return receive


__all__ = ["BodyLimitMiddleware"]
