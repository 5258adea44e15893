"""``synth serve``: settings from the environment, overridden by flags, run under uvicorn."""

from __future__ import annotations

import copy
import sys
from collections.abc import Sequence
from typing import Any

from server.settings import settings_from_env


def serve(
    host: str = "127.0.0.1",
    port: int = 8000,
    db: str | None = None,
    token: str | None = None,
    model_dirs: Sequence[str] = (),
) -> int:
    """Run the service until interrupted; 2 on a configuration error (like any CLI error)."""
    import uvicorn
    from uvicorn.config import STARTUP_FAILURE

    from server.connections import uvicorn_config
    from server.main import create_app

    try:
        settings = settings_from_env()
        changes: dict[str, object] = {}
        if db is not None:
            changes["db_url"] = db
        if token is not None:
            changes["token"] = token
        if model_dirs:
            changes["model_dirs"] = tuple(model_dirs)
        settings = settings.with_(**changes)
    except ValueError as exc:
        print(f"synth serve: error: {exc}", file=sys.stderr)
        return 2
    problem = _check_database(settings.db_url)
    if problem:
        print(f"synth serve: error: {problem}", file=sys.stderr)
        return 2
    if settings.token is None and host not in ("127.0.0.1", "localhost", "::1"):
        print(
            f"synth serve: warning: no token set and listening on {host}: anyone who can reach "
            "it can submit work (set --token or SYNTH_TOKEN)",
            file=sys.stderr,
        )
    config = uvicorn_config(
        create_app(settings), settings, host, port, log_level="info", log_config=_log_config()
    )
    try:
        uvicorn.Server(config).run()
    except SystemExit as exc:
        if exc.code == STARTUP_FAILURE:  # uvicorn logged why (e.g. the port is in use)
            print(f"synth serve: error: cannot listen on {host}:{port}", file=sys.stderr)
            return 2
        raise
    return 0


def _log_config() -> dict[str, Any]:
    """The logging of uvicorn, plus the server's own loggers (jobs recovered, bugs) at INFO."""
    from uvicorn.config import LOGGING_CONFIG

    config = copy.deepcopy(LOGGING_CONFIG)
    config["loggers"]["server"] = {"handlers": ["default"], "level": "INFO", "propagate": False}
    return config


def _check_database(url: str) -> str | None:
    """None if the database at ``url`` opens and has (or gets) the tables, else the problem."""
    from sqlalchemy.engine import make_url
    from sqlalchemy.exc import SQLAlchemyError

    from server.db import PlanStore

    try:
        shown = make_url(url).render_as_string(hide_password=True)
    except Exception:
        return f"not a database URL or path: {url!r}"
    try:
        store = PlanStore(url)
        try:
            store.create_schema()
        finally:
            store.close()
    except (SQLAlchemyError, ImportError) as exc:
        reason = str(getattr(exc, "orig", None) or exc).splitlines()[0]
        return f"cannot open the database {shown}: {reason}"
    return None


__all__ = ["serve"]
