"""Server settings: one frozen pydantic-settings record, from the environment (``SYNTH_*``).

:func:`settings_from_env` reads the ``SYNTH_*`` variables (pydantic-settings' environment
source, prefix ``SYNTH_``); constructing :class:`Settings` directly uses only the values given
and the defaults, never the environment, so a test's settings do not depend on the shell it
runs in. A value that does not validate raises :class:`SettingsError` (a ``ValueError``) whose
message names the variable, e.g. ``SYNTH_WORKERS='many': Input should be a valid integer``.

Routes get the settings through the cached :func:`get_settings` dependency; ``create_app``
overrides it with the settings it was built with, and tests override it again through
``app.dependency_overrides`` when they need to.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from functools import lru_cache
from pathlib import Path
from typing import Annotated, Any

from pydantic import AliasChoices, Field, ValidationError, field_validator, model_validator
from pydantic_settings import (
    BaseSettings,
    EnvSettingsSource,
    NoDecode,
    PydanticBaseSettingsSource,
    SettingsConfigDict,
)
from pydantic_settings.sources.utils import parse_env_vars

DEFAULT_DB = "synth.db"
ENV_PREFIX = "SYNTH_"


def database_url(db: str) -> str:
    """A SQLAlchemy URL for ``db``: a URL is kept, a file path becomes ``sqlite:///PATH``."""
    if "://" in db:
        return db
    return f"sqlite:///{Path(db).expanduser().resolve()}"


def _default_workers() -> int:
    return max(1, min(4, os.cpu_count() or 1))


class SettingsError(ValueError):
    """Settings that do not validate; the message names each offending variable."""


class Settings(BaseSettings):
    """Everything the service is configured with; environment names in brackets.

    ``token`` [SYNTH_TOKEN]: when set, writes (``POST``, ``DELETE``) need
    ``Authorization: Bearer TOKEN``; ``protect_reads`` [SYNTH_PROTECT_READS=1] extends that to
    the read endpoints (``/healthz`` stays open). ``db_url`` [SYNTH_DB]: a SQLAlchemy URL or a
    SQLite file path. ``max_body_bytes`` [SYNTH_MAX_BODY_BYTES] caps every request body (413).
    ``default_trials`` / ``max_trials`` [SYNTH_TRIALS / SYNTH_MAX_TRIALS]: Monte Carlo trials of
    the replay when a request names none, and the most a request may ask for (422 naming
    ``trials`` beyond). ``plan_timeout`` [SYNTH_PLAN_TIMEOUT] [s]: wall-clock budget of one
    planning or replay job once it runs. ``workers`` [SYNTH_WORKERS]: worker processes that run
    jobs. ``model_dirs`` [SYNTH_MODEL_DIRS, ``os.pathsep``-separated]: the only directories a
    task's URDF, SRDF and package references may resolve into. ``worker_memory_mib``
    [SYNTH_WORKER_MEMORY_MIB] [MiB]: address-space cap of each worker (0: none); a job that
    needs more fails with a 422 problem.

    Jobs (:mod:`server.jobs`): ``max_wait`` [SYNTH_MAX_WAIT] [s]: the longest a request may
    wait for a job (``?wait=``); ``max_batch`` [SYNTH_MAX_BATCH]: tasks in one batch;
    ``max_jobs`` [SYNTH_MAX_JOBS]: unfinished jobs in the whole server (503 beyond).
    Fair lanes (:mod:`server.lanes`): ``jobs_per_client`` [SYNTH_JOBS_PER_CLIENT] jobs of one
    client (peer address) run at once (0: ``workers - 1``, at least 1), and
    ``queue_per_client`` [SYNTH_QUEUE_PER_CLIENT] more may be queued (429 beyond).
    Connections (:mod:`server.connections`): ``header_timeout`` [SYNTH_HEADER_TIMEOUT] [s] to
    send a request's headers, from connecting or from the end of the previous response;
    ``keep_alive_timeout`` [SYNTH_KEEP_ALIVE_TIMEOUT] [s] of silence before an idle
    keep-alive connection is closed; ``body_timeout`` [SYNTH_BODY_TIMEOUT] [s] to send a
    request body (408 after); ``max_connections`` [SYNTH_MAX_CONNECTIONS] open at once (503
    beyond).
    """

    model_config = SettingsConfigDict(
        env_prefix=ENV_PREFIX, frozen=True, extra="forbid", populate_by_name=True
    )

    token: str | None = None
    protect_reads: bool = False
    db_url: str = Field(
        default=DEFAULT_DB,
        min_length=1,
        validation_alias=AliasChoices("db_url", f"{ENV_PREFIX}DB"),
    )
    max_body_bytes: int = Field(default=1 << 20, gt=0)
    default_trials: int = Field(
        default=8, ge=0, validation_alias=AliasChoices("default_trials", f"{ENV_PREFIX}TRIALS")
    )
    max_trials: int = Field(default=200, ge=0)
    plan_timeout: float = Field(default=60.0, gt=0)
    workers: int = Field(default_factory=_default_workers, ge=1)
    model_dirs: Annotated[tuple[Path, ...], NoDecode] = ()
    worker_memory_mib: int = Field(default=4096, ge=0)
    max_wait: float = Field(default=30.0, ge=0)
    max_batch: int = Field(default=64, ge=1)
    max_jobs: int = Field(default=1000, ge=1)
    jobs_per_client: int = Field(default=0, ge=0)
    queue_per_client: int = Field(default=32, ge=0)
    header_timeout: float = Field(default=10.0, gt=0)
    keep_alive_timeout: float = Field(default=5.0, gt=0)
    body_timeout: float = Field(default=30.0, gt=0)
    max_connections: int = Field(default=256, ge=1)

    @classmethod
    def settings_customise_sources(
        cls,
        settings_cls: type[BaseSettings],
        init_settings: PydanticBaseSettingsSource,
        env_settings: PydanticBaseSettingsSource,
        dotenv_settings: PydanticBaseSettingsSource,
        file_secret_settings: PydanticBaseSettingsSource,
    ) -> tuple[PydanticBaseSettingsSource, ...]:
        """The values given only: :func:`settings_from_env` adds the environment."""
        return (init_settings,)

    @field_validator("token", mode="before")
    @classmethod
    def _empty_token_is_none(cls, value: Any) -> Any:
        return None if value == "" else value

    @field_validator("db_url")
    @classmethod
    def _url(cls, value: str) -> str:
        return database_url(value)

    @field_validator("model_dirs", mode="before")
    @classmethod
    def _split_dirs(cls, value: Any) -> Any:
        if isinstance(value, str):
            return tuple(p for p in value.split(os.pathsep) if p)
        return value

    @field_validator("model_dirs")
    @classmethod
    def _resolve_dirs(cls, value: tuple[Path, ...]) -> tuple[Path, ...]:
        return tuple(Path(d).expanduser().resolve() for d in value)

    @model_validator(mode="after")
    def _trials_within_maximum(self) -> Settings:
        if self.default_trials > self.max_trials:
            raise ValueError(
                f"the default trials ({self.default_trials}, SYNTH_TRIALS) exceed the maximum "
                f"({self.max_trials}, SYNTH_MAX_TRIALS)"
            )
        return self

    @property
    def client_jobs(self) -> int:
        """Jobs one client may run at once: ``jobs_per_client``, or ``workers - 1`` (>= 1)."""
        return self.jobs_per_client or max(1, self.workers - 1)

    def with_(self, **changes: Any) -> Settings:
        """A validated copy with ``changes`` applied (the CLI's flags over the environment)."""
        return _validated(lambda: type(self)(**{**self.model_dump(), **changes}))


def env_name(field: str) -> str:
    """The environment variable of the settings field ``field`` (``db_url`` → ``SYNTH_DB``)."""
    info = Settings.model_fields.get(field)
    alias = info.validation_alias if info is not None else None
    if isinstance(alias, AliasChoices):
        names = [c for c in alias.choices if isinstance(c, str) and c.startswith(ENV_PREFIX)]
        if names:
            return names[0]
    return f"{ENV_PREFIX}{field.upper()}"


def _validated(build: Any) -> Settings:
    """``build()``, with a :class:`ValidationError` restated per variable."""
    try:
        settings = build()
    except ValidationError as exc:
        lines = []
        for error in exc.errors():
            loc = [str(part) for part in error.get("loc", ())]
            field = loc[0] if loc else ""
            name = env_name(field) if field in Settings.model_fields else field
            shown = f"{name}={error['input']!r}" if "input" in error and field else name
            message = str(error.get("msg", "invalid")).removeprefix("Value error, ")
            lines.append(f"{shown}: {message}" if shown else message)
        raise SettingsError("; ".join(lines)) from None
    assert isinstance(settings, Settings)
    return settings


class _Environment(EnvSettingsSource):
    """pydantic-settings' environment source over a given mapping (default ``os.environ``)."""

    def __init__(self, env: Mapping[str, str]) -> None:
        self._env = env
        super().__init__(Settings)

    def _load_env_vars(self) -> Mapping[str, str | None]:
        return parse_env_vars(
            self._env, self.case_sensitive, self.env_ignore_empty, self.env_parse_none_str
        )


def settings_from_env(env: Mapping[str, str] | None = None) -> Settings:
    """Settings from the ``SYNTH_*`` variables of ``env`` (default: the process's)."""
    values = _Environment(os.environ if env is None else env)()
    return _validated(lambda: Settings(**values))


@lru_cache
def get_settings() -> Settings:
    """The process's settings (from the environment), cached; a FastAPI dependency."""
    return settings_from_env()


__all__ = [
    "DEFAULT_DB",
    "Settings",
    "SettingsError",
    "database_url",
    "env_name",
    "get_settings",
    "settings_from_env",
]
