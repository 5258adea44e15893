"""FastAPI dependencies and their ``Annotated`` aliases: settings, the service, access rules.

Access rule: when a token is configured, every write (``POST``) needs
``Authorization: Bearer TOKEN``; reads (``GET /v1/...``) are open unless ``protect_reads`` is
set, and ``/healthz`` is always open. Without a token everything is open (bind to loopback).
"""

from __future__ import annotations

import difflib
import hmac
from typing import Annotated

from fastapi import Depends, FastAPI, Request
from fastapi.dependencies.models import Dependant
from fastapi.routing import APIRoute
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer

from server.exceptions import InvalidRequest, Unauthorized, UnsupportedMediaType
from server.service import JSON_MEDIA_TYPES, PlanService, is_json_media, media_type
from server.settings import Settings, get_settings

SettingsDep = Annotated[Settings, Depends(get_settings)]

_bearer = HTTPBearer(auto_error=False, description="the server's token (--token / SYNTH_TOKEN)")
Credentials = Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)]


def current_settings(app: FastAPI) -> Settings:
    """The settings routes see, honouring ``app.dependency_overrides`` (for middleware)."""
    provider = app.dependency_overrides.get(get_settings, get_settings)
    settings = provider()
    assert isinstance(settings, Settings)
    return settings


def client_key(request: Request) -> str:
    """The key fair lanes count a request's jobs under: its peer address (host only)."""
    return request.client.host if request.client is not None else "-"


def get_service(request: Request) -> PlanService:
    """The app's :class:`PlanService` (built at startup)."""
    service = request.app.state.service
    assert isinstance(service, PlanService)
    return service


ServiceDep = Annotated[PlanService, Depends(get_service)]


def _check(settings: Settings, credentials: HTTPAuthorizationCredentials | None) -> None:
    if settings.token is None:
        return
    if credentials is None:
        raise Unauthorized("this endpoint needs 'Authorization: Bearer <token>'")
    if not hmac.compare_digest(credentials.credentials.encode(), settings.token.encode()):
        raise Unauthorized("the bearer token is not valid")


def require_writer(settings: SettingsDep, credentials: Credentials) -> None:
    """Writes need the token whenever one is configured."""
    _check(settings, credentials)


def require_reader(settings: SettingsDep, credentials: Credentials) -> None:
    """Reads need the token only when ``protect_reads`` is set."""
    if settings.protect_reads:
        _check(settings, credentials)


def require_json(request: Request) -> None:
    """A JSON body route's media type: JSON (or none), else ``415`` before the body is read.

    Without it a form post reached the body's validation and came back as a ``422`` "Input
    should be a valid dictionary", not the ``415`` docs/api.md promises.
    """
    media = media_type(request.headers.get("content-type"))
    if media and not is_json_media(media):
        raise UnsupportedMediaType(
            f"this endpoint reads a JSON body, not {media!r} (Content-Type: application/json)",
            accepted=sorted(JSON_MEDIA_TYPES),
        )


def _query_names(route: APIRoute) -> set[str]:
    """The query parameters a route takes, its dependencies' included."""
    names: set[str] = set()
    stack: list[Dependant] = [route.dependant]
    while stack:
        dependant = stack.pop()
        names.update(param.alias for param in dependant.query_params)
        stack.extend(dependant.dependencies)
    return names


async def refuse_unknown_query(request: Request) -> None:
    """A query parameter the route does not take, or one given twice, is a ``422`` naming it.

    Ignored, ``POST /v1/plans?trails=500`` planned with the server's default trials and said
    nothing of the typo (the near miss is named). ``?trials=3&trials=5`` took the last one as
    silently: no route takes a list, so a repeated parameter is a client's mistake.
    """
    route = request.scope.get("route")
    if not isinstance(route, APIRoute):
        return
    known = _query_names(route)
    for name in request.query_params:
        given = request.query_params.getlist(name)
        if len(given) > 1:
            raise InvalidRequest(
                f"query parameter {name!r} is given {len(given)} times "
                f"({', '.join(repr(v) for v in given)}); give it once",
                parameter=name,
            )
        if name in known:
            continue
        near = difflib.get_close_matches(name, sorted(known), n=1)
        hint = f"; did you mean {near[0]!r}?" if near else ""
        takes = ", ".join(sorted(known)) or "none"
        raise InvalidRequest(
            f"unknown query parameter {name!r}{hint} ({request.method} {route.path} takes: "
            f"{takes})",
            parameter=name,
        )


Writer = Depends(require_writer)
Reader = Depends(require_reader)
JsonBody = Depends(require_json)
KnownQuery = Depends(refuse_unknown_query)

__all__ = [
    "Credentials",
    "JsonBody",
    "KnownQuery",
    "Reader",
    "ServiceDep",
    "SettingsDep",
    "Writer",
    "client_key",
    "current_settings",
    "get_service",
    "refuse_unknown_query",
    "require_reader",
    "require_writer",
]
