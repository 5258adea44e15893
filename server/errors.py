"""HTTP errors: every failure becomes an RFC 9457 problem document (``application/problem+json``).

One place maps exceptions to statuses (:func:`problem_for`):

====================================  ======  =============================================
exception                             status  extra members
====================================  ======  =============================================
``SpecError``, ``UnitError``          422     ``path``, ``line``
``NoStrategyError``                   422     ``reasons``: ``{candidate, reason}`` each
``ALSyntaxError``                     422     ``line``, ``column``, ``expected``, ``hint``
``ALRuntimeError``                    422     ``line``, ``column``
any other ``SynthError``              422     its structured fields
request schema errors (FastAPI)       422     ``errors`` (``loc`` and ``msg`` per field)
:class:`InvalidRequest`               422     ``parameter``
:class:`MemoryBudgetExceeded`         422     ``limit_mib``
:class:`Unauthorized`                 401     (``WWW-Authenticate: Bearer``)
:class:`NotFound`, unknown route      404
:class:`PayloadTooLarge`              413     ``limit_bytes``
:class:`UnsupportedMediaType`         415     ``accepted``
:class:`ServiceBusy`                  503     (``Retry-After``)
:class:`JobLost`                      503     (a job's problem, never a response)
:class:`JobCancelled`                 409     (a job's problem, never a response)
:class:`TimeBudgetExceeded`           504     ``budget_seconds``
anything else, :class:`WorkerFailed`  500     nothing but a request id; the traceback is logged
:class:`RequestTimeout`               408     (``Connection: close``)
:class:`TooManyRequests`              429     ``running``, ``waiting`` (``Retry-After``)
====================================  ======  =============================================

An exception no handler claims is answered by :class:`ProblemMiddleware`, inside Starlette's
``ServerErrorMiddleware``: that one re-raises after answering, and uvicorn then closes the
connection, so a 500 would drop the client's keep-alive connection.
"""

from __future__ import annotations

import logging
import math
import re
import uuid
from collections.abc import Mapping, Sequence
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from server.exceptions import (
    ApiError,
    InvalidRequest,
    MemoryBudgetExceeded,
    NotFound,
    PayloadTooLarge,
    RequestTimeout,
    ServiceBusy,
    TimeBudgetExceeded,
    TooManyRequests,
    Unauthorized,
    UnsupportedMediaType,
    WorkerFailed,
)
from synth import exceptions as sx

log = logging.getLogger("server")

PROBLEM_MEDIA_TYPE = "application/problem+json"


_TITLES: tuple[tuple[str, str], ...] = (
    ("SpecError", "Invalid task specification"),
    ("UnitError", "Invalid task specification"),
    ("NoStrategyError", "No feasible strategy"),
    ("ALSyntaxError", "AL syntax error"),
    ("ALRuntimeError", "AL runtime error"),
)

# Structured fields of SynthError subclasses worth showing a client, in display order.
_FIELDS = (
    "path",
    "line",
    "column",
    "expected",
    "hint",
    "context",
    "problem",
    "task",
    "reasons",
    "rejected",
    "name",
    "known",
    "source",
    "reason",
    "field",
    "translation",
)


def _slug(name: str) -> str:
    name = name.removesuffix("Error")
    return re.sub(r"(?<!^)(?=[A-Z])", "-", name).lower() or "synth"


def _text(value: object, limit: int = 500) -> str:
    text = str(value)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def jsonable(value: Any, depth: int = 0) -> Any:
    """``value`` as plain JSON: records by ``to_json``, tuples as lists, other objects as text."""
    if depth > 8:
        return _text(value)
    if value is None or isinstance(value, bool | int | str):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else str(value)
    if hasattr(value, "to_json"):
        try:
            return jsonable(value.to_json(), depth + 1)
        except Exception:
            return _text(value)
    if isinstance(value, Mapping):
        return {str(k): jsonable(v, depth + 1) for k, v in value.items()}
    if isinstance(value, list | tuple | set | frozenset):
        return [jsonable(v, depth + 1) for v in value]
    return _text(value)


def problem_for(exc: BaseException) -> tuple[int, dict[str, Any], Mapping[str, str]]:
    """Status, problem document and headers for ``exc`` (the one mapping of the service)."""
    if isinstance(exc, ApiError):
        body = {
            "type": f"urn:synth:problem:{_slug(type(exc).__name__)}",
            "title": exc.title,
            "status": exc.status,
            "detail": exc.detail,
            **{k: jsonable(v) for k, v in exc.extra.items()},
        }
        return exc.status, body, exc.headers
    if isinstance(exc, sx.SynthError):
        name = type(exc).__name__
        title = next((t for n, t in _TITLES if isinstance(exc, getattr(sx, n, ()))), None)
        body = {
            "type": f"urn:synth:problem:{_slug(name)}",
            "title": title or "Task cannot be processed",
            "status": 422,
            "detail": str(exc),
        }
        if isinstance(exc, sx.SpecError):
            body["message"] = exc.detail
        for field in _FIELDS:
            if field in vars(exc):
                body[field] = jsonable(vars(exc)[field])
        reasons = body.get("reasons")
        if isinstance(reasons, list) and all(
            isinstance(r, list) and len(r) == 2 for r in reasons
        ):  # NoStrategyError: (candidate, reason) pairs
            body["reasons"] = [{"candidate": c, "reason": r} for c, r in reasons]
            body["detail"] = str(exc).split("\n", 1)[0].rstrip(":")
        return 422, body, {}
    request_id = uuid.uuid4().hex[:12]
    body = {
        "type": "urn:synth:problem:internal",
        "title": "Internal error",
        "status": 500,
        "detail": f"an internal error occurred (request id {request_id}); it has been logged",
        "request_id": request_id,
    }
    return 500, body, {}


def _logged(exc: BaseException) -> tuple[int, dict[str, Any], Mapping[str, str]]:
    """:func:`problem_for`, logging a genuine bug (500) with its traceback."""
    status, body, headers = problem_for(exc)
    if status == 500:
        remote = getattr(exc, "remote_traceback", "")
        log.error(
            "internal error (request id %s): %s%s",
            body.get("request_id", "-"),
            exc,
            f"\nworker traceback:\n{remote}" if remote else "",
            exc_info=(type(exc), exc, exc.__traceback__),
        )
    return status, body, headers


def problem_document(exc: BaseException) -> dict[str, Any]:
    """The problem document of ``exc`` (a job's outcome, a batch item's answer); bugs logged."""
    return _logged(exc)[1]


def problem_response(exc: BaseException) -> JSONResponse:
    """The response for ``exc``; genuine bugs are logged with their traceback."""
    status, body, headers = _logged(exc)
    return JSONResponse(
        body, status_code=status, headers=dict(headers), media_type=PROBLEM_MEDIA_TYPE
    )


async def _on_exception(_request: Request, exc: Exception) -> JSONResponse:
    return problem_response(exc)


def validation_problem(errors: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """The 422 problem document of pydantic validation ``errors`` (``loc`` and ``msg`` each)."""
    listed = [
        {"loc": jsonable(e.get("loc", ())), "msg": str(e.get("msg", "invalid value"))}
        for e in errors
    ]
    first = listed[0] if listed else {"loc": [], "msg": "invalid request"}
    where = ".".join(str(p) for p in first["loc"])
    return {
        "type": "urn:synth:problem:request",
        "title": "Invalid request",
        "status": 422,
        "detail": f"{where}: {first['msg']}" if where else first["msg"],
        "errors": listed,
    }


async def _on_request_validation(_request: Request, exc: Exception) -> JSONResponse:
    assert isinstance(exc, RequestValidationError)
    return JSONResponse(
        validation_problem(exc.errors()), status_code=422, media_type=PROBLEM_MEDIA_TYPE
    )


async def _on_http_exception(_request: Request, exc: Exception) -> JSONResponse:
    assert isinstance(exc, StarletteHTTPException)
    detail = str(exc.detail)
    cause = exc.__cause__
    if exc.status_code == 400 and isinstance(cause, UnicodeDecodeError):
        # FastAPI's "There was an error parsing the body" does not say what was wrong
        detail = f"the body is not UTF-8 text (byte {cause.start}): send JSON as UTF-8"
    body = {
        "type": "about:blank",
        "title": _HTTP_TITLES.get(exc.status_code, "HTTP error"),
        "status": exc.status_code,
        "detail": detail,
    }
    return JSONResponse(
        body,
        status_code=exc.status_code,
        headers=dict(exc.headers or {}),
        media_type=PROBLEM_MEDIA_TYPE,
    )


_HTTP_TITLES = {400: "Bad request", 404: "Not found", 405: "Method not allowed"}


class ProblemMiddleware:
    """Answer any exception that escapes the app with its problem document, and swallow it.

    The connection stays open (keep-alive) because nothing re-raises to the server. An
    exception after the response started cannot be answered any more: it is re-raised.
    """

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Run the app; turn an unhandled exception into a problem response."""
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        started = False

        async def tracking_send(message: Message) -> None:
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
            await send(message)

        try:
            await self.app(scope, receive, tracking_send)
        except Exception as exc:
            if started:
                raise
            await problem_response(exc)(scope, receive, send)


def install_error_handlers(app: FastAPI) -> None:
    """Route every exception through :func:`problem_for` (the last one is the catch-all).

    Call it after every other ``add_middleware``: :class:`ProblemMiddleware` must be the
    outermost of the app's own middleware, so that it also answers their exceptions.
    """
    app.add_exception_handler(ApiError, _on_exception)
    app.add_exception_handler(sx.SynthError, _on_exception)
    app.add_exception_handler(RequestValidationError, _on_request_validation)
    app.add_exception_handler(StarletteHTTPException, _on_http_exception)
    app.add_exception_handler(Exception, _on_exception)
    app.add_middleware(ProblemMiddleware)


__all__ = [
    "PROBLEM_MEDIA_TYPE",
    "ApiError",
    "InvalidRequest",
    "MemoryBudgetExceeded",
    "NotFound",
    "PayloadTooLarge",
    "ProblemMiddleware",
    "RequestTimeout",
    "ServiceBusy",
    "TimeBudgetExceeded",
    "TooManyRequests",
    "Unauthorized",
    "UnsupportedMediaType",
    "WorkerFailed",
    "install_error_handlers",
    "jsonable",
    "problem_document",
    "problem_for",
    "problem_response",
    "validation_problem",
]
