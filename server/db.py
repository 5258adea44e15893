"""Persistence of plans: SQLAlchemy 2.x, SQLite (WAL) by default, any SQLAlchemy URL.

A plan row keeps the spec as submitted, the canonical spec JSON, the planner's result JSON, the
AL program, the replay report and a content hash of (canonical spec, options, synth version)
so identical submissions are answered from the store. :meth:`PlanStore.add` commits before it
returns, so a plan the server acknowledged with 201 survives a crash: SQLite runs with
``journal_mode=WAL`` and ``synchronous=FULL``.
"""

from __future__ import annotations

import json
import uuid
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

from sqlalchemy import (
    DateTime,
    Engine,
    Integer,
    String,
    Text,
    create_engine,
    event,
    select,
)
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column, sessionmaker
from sqlalchemy.pool import StaticPool


class Base(DeclarativeBase):
    """Declarative base of the server's tables."""


class PlanRow(Base):
    """One stored plan. ``seq`` orders the listing; ``id`` is the public, unguessable id."""

    __tablename__ = "plans"

    seq: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    id: Mapped[str] = mapped_column(String(32), unique=True, index=True)
    content_hash: Mapped[str] = mapped_column(String(64), unique=True, index=True)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    task_name: Mapped[str] = mapped_column(Text)
    spec_text: Mapped[str] = mapped_column(Text)
    spec_media_type: Mapped[str] = mapped_column(String(64))
    spec_json: Mapped[str] = mapped_column(Text)
    options_json: Mapped[str] = mapped_column(Text)
    result_json: Mapped[str] = mapped_column(Text)
    program_text: Mapped[str] = mapped_column(Text)
    validation_json: Mapped[str] = mapped_column(Text)


@dataclass(frozen=True)
class StoredPlan:
    """A plan as read back from the store (JSON columns decoded)."""

    id: str
    seq: int
    content_hash: str
    created_at: datetime
    task_name: str
    spec_text: str
    spec_media_type: str
    spec: dict[str, Any]
    options: dict[str, Any]
    result: dict[str, Any]
    program: str
    validation: dict[str, Any] | None


@dataclass(frozen=True)
class NewPlan:
    """What :meth:`PlanStore.add` stores (everything but the id, sequence and time)."""

    content_hash: str
    task_name: str
    spec_text: str
    spec_media_type: str
    spec: dict[str, Any]
    options: dict[str, Any]
    result: dict[str, Any]
    program: str
    validation: dict[str, Any] | None


def make_engine(url: str) -> Engine:
    """An engine for ``url``; SQLite gets WAL, ``synchronous=FULL`` and a busy timeout."""
    if not url.startswith("sqlite"):
        return create_engine(url, pool_pre_ping=True)
    memory = url in ("sqlite://", "sqlite:///:memory:") or "mode=memory" in url
    engine = create_engine(
        url,
        connect_args={"check_same_thread": False, "timeout": 30},
        poolclass=StaticPool if memory else None,
    )

    @event.listens_for(engine, "connect")
    def _pragmas(dbapi_connection: Any, _record: Any) -> None:
        cursor = dbapi_connection.cursor()
        if not memory:
            cursor.execute("PRAGMA journal_mode=WAL")
        cursor.execute("PRAGMA synchronous=FULL")
        cursor.execute("PRAGMA foreign_keys=ON")
        cursor.close()

    return engine


def _stored(row: PlanRow) -> StoredPlan:
    created = row.created_at
    if created.tzinfo is None:  # SQLite drops the zone; we only ever store UTC
        created = created.replace(tzinfo=UTC)
    return StoredPlan(
        id=row.id,
        seq=row.seq,
        content_hash=row.content_hash,
        created_at=created,
        task_name=row.task_name,
        spec_text=row.spec_text,
        spec_media_type=row.spec_media_type,
        spec=json.loads(row.spec_json),
        options=json.loads(row.options_json),
        result=json.loads(row.result_json),
        program=row.program_text,
        validation=json.loads(row.validation_json),
    )


class PlanStore:
    """Plans in a database; every method opens and closes its own session (thread-safe)."""

    def __init__(self, url: str) -> None:
        self.url = url
        self.engine = make_engine(url)
        self._sessions = sessionmaker(self.engine, expire_on_commit=False)

    def create_schema(self) -> None:
        """Create missing tables (idempotent)."""
        Base.metadata.create_all(self.engine)

    def close(self) -> None:
        """Release the connection pool."""
        self.engine.dispose()

    def ping(self) -> bool:
        """True when the database answers a trivial query."""
        try:
            with self._sessions() as session:
                session.execute(select(1))
            return True
        except Exception:
            return False

    def add(self, plan: NewPlan) -> tuple[StoredPlan, bool]:
        """Store ``plan`` and commit; return it and True, or the stored twin and False.

        The twin is the plan already stored under the same content hash (a concurrent or
        earlier identical submission).
        """
        row = PlanRow(
            id=uuid.uuid4().hex,
            content_hash=plan.content_hash,
            created_at=datetime.now(UTC),
            task_name=plan.task_name,
            spec_text=plan.spec_text,
            spec_media_type=plan.spec_media_type,
            spec_json=json.dumps(plan.spec, sort_keys=True),
            options_json=json.dumps(plan.options, sort_keys=True),
            result_json=json.dumps(plan.result),
            program_text=plan.program,
            validation_json=json.dumps(plan.validation),
        )
        try:
            with self._sessions() as session, session.begin():
                session.add(row)
        except IntegrityError:
            twin = self.by_hash(plan.content_hash)
            if twin is None:  # the conflict was not the hash: a genuine fault
                raise
            return twin, False
        return _stored(row), True

    def get(self, plan_id: str) -> StoredPlan | None:
        """The plan with public id ``plan_id``, or None."""
        with self._sessions() as session:
            row = session.scalars(select(PlanRow).where(PlanRow.id == plan_id)).first()
            return None if row is None else _stored(row)

    def by_hash(self, content_hash: str) -> StoredPlan | None:
        """The plan stored under ``content_hash``, or None."""
        with self._sessions() as session:
            row = session.scalars(
                select(PlanRow).where(PlanRow.content_hash == content_hash)
            ).first()
            return None if row is None else _stored(row)

    def page(self, limit: int, after: int | None = None) -> tuple[list[StoredPlan], int | None]:
        """Up to ``limit`` plans, newest first, older than ``after``; and the next cursor."""
        with self._sessions() as session:
            query = select(PlanRow).order_by(PlanRow.seq.desc()).limit(limit + 1)
            if after is not None:
                query = query.where(PlanRow.seq < after)
            rows = list(session.scalars(query))
        more = len(rows) > limit
        plans = [_stored(r) for r in rows[:limit]]
        return plans, (plans[-1].seq if more and plans else None)


__all__ = ["NewPlan", "PlanRow", "PlanStore", "StoredPlan", "make_engine"]
