"""The server's own failures (not the task's), as exceptions with an HTTP status.

Free of FastAPI so worker processes can raise and ship them; :mod:`server.errors` maps them
(and synth's exceptions) to responses.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar


class ApiError(Exception):
    """A failure of the service itself (not of the task): status, title, detail, extras."""

    status = 500
    title = "Internal error"
    headers: ClassVar[Mapping[str, str]] = {}

    def __init__(self, detail: str, **extra: Any) -> None:
        super().__init__(detail)
        self.detail = detail
        self.extra = extra


class InvalidRequest(ApiError):
    """A request option out of the server's bounds (e.g. more trials than it allows)."""

    status = 422
    title = "Invalid request"


class Unauthorized(ApiError):
    """A write (or protected read) without the configured bearer token."""

    status = 401
    title = "Unauthorized"
    headers: ClassVar[Mapping[str, str]] = {"WWW-Authenticate": "Bearer"}


class NotFound(ApiError):
    """No plan or job with that id."""

    status = 404
    title = "Not found"


class PayloadTooLarge(ApiError):
    """The request body is over the configured limit."""

    status = 413
    title = "Request body too large"


class UnsupportedMediaType(ApiError):
    """A body in a media type the endpoint does not read."""

    status = 415
    title = "Unsupported media type"


class RequestTimeout(ApiError):
    """The request body did not arrive within the body deadline (a slow or stalled client)."""

    status = 408
    title = "Request timeout"
    headers: ClassVar[Mapping[str, str]] = {"Connection": "close"}


class TooManyRequests(ApiError):
    """The client already has as many jobs running and waiting as the server lets one client."""

    status = 429
    title = "Too many requests from this client"
    headers: ClassVar[Mapping[str, str]] = {"Retry-After": "5"}


class ServiceBusy(ApiError):
    """No worker became free within the time budget (or none could be started)."""

    status = 503
    title = "Service busy"
    headers: ClassVar[Mapping[str, str]] = {"Retry-After": "5"}


class JobLost(ApiError):
    """A job's outcome is unknown: the server stopped abruptly while it ran (the job's problem)."""

    status = 503
    title = "Job lost"


class JobCancelled(ApiError):
    """A job was cancelled (``DELETE``) before it finished (the job's problem)."""

    status = 409
    title = "Job cancelled"


class TimeBudgetExceeded(ApiError):
    """A planning or replay job ran past the time budget; its worker was stopped."""

    status = 504
    title = "Time budget exceeded"


class MemoryBudgetExceeded(ApiError):
    """A job tried to allocate more than a worker may (the task is too large to process)."""

    status = 422
    title = "Task exceeds the server's memory budget"


class WorkerFailed(RuntimeError):
    """A worker process died or a job failed with a non-synth exception: a bug, answered 500.

    ``remote_traceback`` is the worker's traceback (logged, never sent to the client).
    """

    def __init__(self, message: str, remote_traceback: str = "") -> None:
        super().__init__(message)
        self.remote_traceback = remote_traceback


__all__ = [
    "ApiError",
    "InvalidRequest",
    "JobCancelled",
    "JobLost",
    "MemoryBudgetExceeded",
    "NotFound",
    "PayloadTooLarge",
    "RequestTimeout",
    "ServiceBusy",
    "TimeBudgetExceeded",
    "TooManyRequests",
    "Unauthorized",
    "UnsupportedMediaType",
    "WorkerFailed",
]
