"""Server settings: one frozen record, read from the environment (``SYNTH_*``) or the CLI.

Routes get the settings through the cached :func:`get_settings` dependency; ``create_app``
overrides it with the settings it was built with, and tests override it again through
``app.dependency_overrides`` when they need to.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from functools import lru_cache
from pathlib import Path
from typing import Any

DEFAULT_DB = "synth.db"


def database_url(db: str) -> str:
    """A SQLAlchemy URL for ``db``: a URL is kept, a file path becomes ``sqlite:///PATH``."""
    if "://" in db:
        return db
    return f"sqlite:///{Path(db).expanduser().resolve()}"


@dataclass(frozen=True)
class Settings:
    """Everything the service is configured with; environment names in brackets.

    ``token`` [SYNTH_TOKEN]: when set, write endpoints need ``Authorization: Bearer TOKEN``;
    ``protect_reads`` [SYNTH_PROTECT_READS=1] extends that to the read endpoints (``/healthz``
    stays open). ``db_url`` [SYNTH_DB]: a SQLAlchemy URL or a SQLite file path.
    ``max_body_bytes`` [SYNTH_MAX_BODY_BYTES] caps every request body (413 above it).
    ``default_trials`` / ``max_trials`` [SYNTH_TRIALS / SYNTH_MAX_TRIALS]: Monte Carlo trials of
    the replay when a request names none, and the most a request may ask for.
    ``plan_timeout`` [SYNTH_PLAN_TIMEOUT] [s]: wall-clock budget of one planning or replay job,
    also the longest a request waits for a free worker. ``workers`` [SYNTH_WORKERS]: worker
    processes that run jobs. ``model_dirs`` [SYNTH_MODEL_DIRS, ``os.pathsep``-separated]: the
    only directories a task's URDF, SRDF and package references may resolve into.
    ``worker_memory_mib`` [SYNTH_WORKER_MEMORY_MIB] [MiB]: address-space cap of each worker
    (0: none); a job that needs more is refused with 422.

    Fair lanes (:mod:`server.lanes`): ``jobs_per_client`` [SYNTH_JOBS_PER_CLIENT] jobs of one
    client (peer address) run at once (0: ``workers - 1``, at least 1), and
    ``queue_per_client`` [SYNTH_QUEUE_PER_CLIENT] more may wait (429 beyond).
    Connections (:mod:`server.connections`): ``header_timeout`` [SYNTH_HEADER_TIMEOUT] [s] to
    send a request's headers, from connecting or from the end of the previous response;
    ``keep_alive_timeout`` [SYNTH_KEEP_ALIVE_TIMEOUT] [s] of silence before an idle
    keep-alive connection is closed; ``body_timeout`` [SYNTH_BODY_TIMEOUT] [s] to send a
    request body (408 after); ``max_connections`` [SYNTH_MAX_CONNECTIONS] open at once (503
    beyond).
    """

    token: str | None = None
    protect_reads: bool = False
    db_url: str = field(default_factory=lambda: database_url(DEFAULT_DB))
    max_body_bytes: int = 1 << 20
    default_trials: int = 8
    max_trials: int = 200
    plan_timeout: float = 60.0
    workers: int = field(default_factory=lambda: max(1, min(4, os.cpu_count() or 1)))
    model_dirs: tuple[Path, ...] = ()
    worker_memory_mib: int = 4096
    jobs_per_client: int = 0
    queue_per_client: int = 4
    header_timeout: float = 10.0
    keep_alive_timeout: float = 5.0
    body_timeout: float = 30.0
    max_connections: int = 256

    def __post_init__(self) -> None:
        if self.token == "":
            object.__setattr__(self, "token", None)
        object.__setattr__(self, "db_url", database_url(self.db_url))
        object.__setattr__(
            self, "model_dirs", tuple(Path(d).expanduser().resolve() for d in self.model_dirs)
        )
        if self.max_body_bytes <= 0:
            raise ValueError("max_body_bytes must be positive")
        if not 0 <= self.default_trials <= self.max_trials:
            raise ValueError("need 0 <= default_trials <= max_trials")
        if not self.plan_timeout > 0:
            raise ValueError("plan_timeout must be positive [s]")
        if self.workers < 1:
            raise ValueError("workers must be at least 1")
        if self.worker_memory_mib < 0:
            raise ValueError("worker_memory_mib must be >= 0 (0: no cap)")
        if self.jobs_per_client < 0 or self.queue_per_client < 0:
            raise ValueError("jobs_per_client and queue_per_client must be >= 0")
        for name in ("header_timeout", "keep_alive_timeout", "body_timeout"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be positive [s]")
        if self.max_connections < 1:
            raise ValueError("max_connections must be at least 1")

    @property
    def client_jobs(self) -> int:
        """Jobs one client may run at once: ``jobs_per_client``, or ``workers - 1`` (>= 1)."""
        return self.jobs_per_client or max(1, self.workers - 1)

    def with_(self, **changes: Any) -> Settings:
        """A copy with ``changes`` applied (the CLI's flags over the environment)."""
        return replace(self, **changes)


def settings_from_env(env: Mapping[str, str] | None = None) -> Settings:
    """Settings from ``SYNTH_*`` variables; unset ones keep their defaults."""
    env = os.environ if env is None else env
    kwargs: dict[str, Any] = {}
    if "SYNTH_TOKEN" in env:
        kwargs["token"] = env["SYNTH_TOKEN"]
    if "SYNTH_PROTECT_READS" in env:
        kwargs["protect_reads"] = env["SYNTH_PROTECT_READS"].strip().lower() in ("1", "true", "yes")
    if "SYNTH_DB" in env:
        kwargs["db_url"] = env["SYNTH_DB"]
    for name, key, kind in (
        ("SYNTH_MAX_BODY_BYTES", "max_body_bytes", int),
        ("SYNTH_TRIALS", "default_trials", int),
        ("SYNTH_MAX_TRIALS", "max_trials", int),
        ("SYNTH_PLAN_TIMEOUT", "plan_timeout", float),
        ("SYNTH_WORKERS", "workers", int),
        ("SYNTH_WORKER_MEMORY_MIB", "worker_memory_mib", int),
        ("SYNTH_JOBS_PER_CLIENT", "jobs_per_client", int),
        ("SYNTH_QUEUE_PER_CLIENT", "queue_per_client", int),
        ("SYNTH_HEADER_TIMEOUT", "header_timeout", float),
        ("SYNTH_KEEP_ALIVE_TIMEOUT", "keep_alive_timeout", float),
        ("SYNTH_BODY_TIMEOUT", "body_timeout", float),
        ("SYNTH_MAX_CONNECTIONS", "max_connections", int),
    ):
        if name in env:
            try:
                kwargs[key] = kind(env[name])
            except ValueError:
                raise ValueError(f"{name}={env[name]!r} is not a valid {kind.__name__}") from None
    if env.get("SYNTH_MODEL_DIRS"):
        kwargs["model_dirs"] = tuple(p for p in env["SYNTH_MODEL_DIRS"].split(os.pathsep) if p)
    return Settings(**kwargs)


@lru_cache
def get_settings() -> Settings:
    """The process's settings (from the environment), cached; a FastAPI dependency."""
    return settings_from_env()


__all__ = ["DEFAULT_DB", "Settings", "database_url", "get_settings", "settings_from_env"]
