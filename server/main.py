"""The FastAPI application: :func:`create_app` composes settings, routers, limits and errors.

``synth serve`` runs ``create_app(settings)`` under uvicorn. At startup the app opens the
database (creating tables), starts the worker processes and recovers the jobs of the previous
run (:mod:`server.jobs`: running ones are lost, queued ones queued again); at shutdown it stops
the jobs (running ones go back to the queue), then the workers.

The interactive docs (``/docs``: Swagger UI, ``/redoc``: ReDoc) load their scripts and styles
from ``/static/`` (vendored in ``server/static/``, see its README), never from a CDN, so they
work on a network without internet access.
"""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

from fastapi import FastAPI
from fastapi.openapi.docs import get_redoc_html, get_swagger_ui_html
from fastapi.responses import HTMLResponse
from fastapi.staticfiles import StaticFiles

import synth
from server import service
from server.db import PlanStore
from server.deps import KnownQuery, current_settings
from server.errors import install_error_handlers
from server.lanes import Lanes
from server.limits import BodyLimitMiddleware
from server.routers import health, jobs, pictures, plans, replays
from server.settings import Settings, get_settings
from server.workers import WorkerPool

STATIC = Path(__file__).resolve().parent / "static"

DESCRIPTION = """\
Submit a pin-in-hole task spec; get an AL program planned after R. H. Taylor (1976),
proven by replaying it on a simulated arm. Planning and replays run as jobs: a submission is
answered `202` with the job's URL, which you poll (or long-poll with `?wait=S`) until it is
`done` or `failed`. See `docs/api.md` for the job flow, the access rule, limits and curl
examples. Errors are RFC 9457 problem documents (`application/problem+json`).
"""


def create_app(settings: Settings | None = None) -> FastAPI:
    """The service configured by ``settings`` (default: :func:`get_settings`, the environment)."""
    settings = settings if settings is not None else get_settings()

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        store = PlanStore(settings.db_url)
        await asyncio.to_thread(store.create_schema)
        await asyncio.to_thread(service.warm_up_parser)
        pool = WorkerPool(
            settings.workers,
            warmup="server.service:warm_up",
            memory_limit=settings.worker_memory_mib * 2**20,
        )
        await pool.start()
        lanes = Lanes(settings.workers, settings.client_jobs, settings.queue_per_client)
        app.state.service = service.PlanService(store, pool, lanes, settings)
        await app.state.service.jobs.start()
        try:
            yield
        finally:
            pool.stop_replacing()
            await app.state.service.jobs.close()
            await pool.close()
            store.close()

    app = FastAPI(
        title="synth",
        version=synth.__version__,
        description=DESCRIPTION,
        lifespan=lifespan,
        docs_url=None,
        redoc_url=None,
    )
    app.dependency_overrides[get_settings] = lambda: settings
    app.add_middleware(
        BodyLimitMiddleware,
        limit=lambda _scope: current_settings(app).max_body_bytes,
        timeout=lambda _scope: current_settings(app).body_timeout,
    )
    install_error_handlers(app)  # last: its middleware wraps the others
    app.mount("/static", StaticFiles(directory=STATIC), name="static")
    _add_docs(app)
    app.include_router(health.router, dependencies=[KnownQuery])
    app.include_router(plans.router, dependencies=[KnownQuery])
    app.include_router(jobs.router, dependencies=[KnownQuery])
    app.include_router(replays.router, dependencies=[KnownQuery])
    app.include_router(pictures.router, dependencies=[KnownQuery])
    return app


def _add_docs(app: FastAPI) -> None:
    """``/docs`` (Swagger UI) and ``/redoc`` (ReDoc), from the vendored assets only."""
    openapi_url = app.openapi_url or "/openapi.json"

    @app.get("/docs", include_in_schema=False)
    async def swagger_ui() -> HTMLResponse:
        return get_swagger_ui_html(
            openapi_url=openapi_url,
            title=f"{app.title} — Swagger UI",
            swagger_js_url="/static/swagger-ui/swagger-ui-bundle.js",
            swagger_css_url="/static/swagger-ui/swagger-ui.css",
            swagger_favicon_url="/static/swagger-ui/favicon-32x32.png",
        )

    @app.get("/redoc", include_in_schema=False)
    async def redoc() -> HTMLResponse:
        return get_redoc_html(
            openapi_url=openapi_url,
            title=f"{app.title} — ReDoc",
            redoc_js_url="/static/redoc/redoc.standalone.js",
            redoc_favicon_url="/static/swagger-ui/favicon-32x32.png",
            with_google_fonts=False,
        )


__all__ = ["create_app"]
