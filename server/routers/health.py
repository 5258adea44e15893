"""``/healthz``: liveness, database, worker and job state."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter

from server.deps import ServiceDep
from server.schemas import HealthOut

router = APIRouter(tags=["health"])


@router.get("/healthz", response_model=HealthOut, summary="Health (always open)")
async def healthz(service: ServiceDep) -> dict[str, Any]:
    """``status`` is ``ok`` when the database answers and at least one worker runs."""
    return await service.health()


__all__ = ["router"]
