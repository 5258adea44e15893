"""Persistence of plans and jobs: SQLAlchemy 2.x, SQLite (WAL) by default, any SQLAlchemy URL.

A plan row keeps the spec as submitted, the canonical spec JSON, the planner's result JSON, the
AL program, the replay report and a content hash of (canonical spec, options, synth version)
so identical submissions are answered from the store. A job row (:mod:`server.jobs`) keeps a
submitted piece of work: its kind, state, times, the input the worker needs (``payload``) and,
once finished, its result or problem document. Every method commits before it returns, so a
plan or job the server acknowledged survives a crash: SQLite runs with ``journal_mode=WAL`` and
``synchronous=FULL``.
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
    delete,
    event,
    select,
    update,
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


JOB_STATES = ("queued", "running", "done", "failed", "lost", "cancelled")
UNFINISHED = ("queued", "running")  # the other states are final


class JobRow(Base):
    """One job: a plan or replay the server accepted, its state and (once final) its outcome."""

    __tablename__ = "jobs"

    seq: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    id: Mapped[str] = mapped_column(String(32), unique=True, index=True)
    kind: Mapped[str] = mapped_column(String(16))
    state: Mapped[str] = mapped_column(String(16), index=True)
    client: Mapped[str] = mapped_column(Text)
    created_at: Mapped[datetime] = mapped_column(DateTime(timezone=True))
    started_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)
    finished_at: Mapped[datetime | None] = mapped_column(DateTime(timezone=True), nullable=True)
    attempts: Mapped[int] = mapped_column(Integer, default=0)
    task_name: Mapped[str | None] = mapped_column(Text, nullable=True)
    content_hash: Mapped[str | None] = mapped_column(String(64), nullable=True)
    options_json: Mapped[str] = mapped_column(Text)
    payload_json: Mapped[str] = mapped_column(Text)
    plan_id: Mapped[str | None] = mapped_column(String(32), nullable=True)
    result_json: Mapped[str | None] = mapped_column(Text, nullable=True)
    problem_json: Mapped[str | None] = mapped_column(Text, nullable=True)


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


@dataclass(frozen=True)
class NewJob:
    """What :meth:`PlanStore.add_job` stores: the work and who asked for it."""

    kind: str
    client: str
    task_name: str | None
    content_hash: str | None
    options: dict[str, Any]
    payload: dict[str, Any]


@dataclass(frozen=True)
class StoredJob:
    """A job as read back from the store (JSON columns decoded)."""

    id: str
    seq: int
    kind: str
    state: str
    client: str
    created_at: datetime
    started_at: datetime | None
    finished_at: datetime | None
    attempts: int
    task_name: str | None
    content_hash: str | None
    options: dict[str, Any]
    payload: dict[str, Any]
    plan_id: str | None
    result: dict[str, Any] | None
    problem: dict[str, Any] | None

    @property
    def finished(self) -> bool:
        """True in a final state (done, failed, lost, cancelled)."""
        return self.state not in UNFINISHED


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


def _utc(moment: datetime) -> datetime:
    """``moment`` with its zone: SQLite drops it, and we only ever store UTC."""
    return moment if moment.tzinfo is not None else moment.replace(tzinfo=UTC)


def _stored(row: PlanRow) -> StoredPlan:
    return StoredPlan(
        id=row.id,
        seq=row.seq,
        content_hash=row.content_hash,
        created_at=_utc(row.created_at),
        task_name=row.task_name,
        spec_text=row.spec_text,
        spec_media_type=row.spec_media_type,
        spec=json.loads(row.spec_json),
        options=json.loads(row.options_json),
        result=json.loads(row.result_json),
        program=row.program_text,
        validation=json.loads(row.validation_json),
    )


def _json_or_none(text: str | None) -> Any:
    return None if text is None else json.loads(text)


def _stored_job(row: JobRow) -> StoredJob:
    return StoredJob(
        id=row.id,
        seq=row.seq,
        kind=row.kind,
        state=row.state,
        client=row.client,
        created_at=_utc(row.created_at),
        started_at=None if row.started_at is None else _utc(row.started_at),
        finished_at=None if row.finished_at is None else _utc(row.finished_at),
        attempts=row.attempts,
        task_name=row.task_name,
        content_hash=row.content_hash,
        options=json.loads(row.options_json),
        payload=json.loads(row.payload_json),
        plan_id=row.plan_id,
        result=_json_or_none(row.result_json),
        problem=_json_or_none(row.problem_json),
    )


def _dumps(value: Any) -> str | None:
    return None if value is None else json.dumps(value)


class PlanStore:
    """Plans and jobs in a database; every method opens and closes its own session (thread-safe)."""

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

    def delete_plan(self, plan_id: str) -> bool:
        """Delete the plan ``plan_id``; False when there is none. Jobs keep its id."""
        with self._sessions() as session, session.begin():
            gone = session.execute(delete(PlanRow).where(PlanRow.id == plan_id))
        return bool(getattr(gone, "rowcount", 0))

    # -- jobs ---------------------------------------------------------------------------------

    def add_job(
        self,
        job: NewJob,
        *,
        state: str = "queued",
        plan_id: str | None = None,
        result: dict[str, Any] | None = None,
    ) -> StoredJob:
        """Store ``job`` (queued, or already ``done`` with its outcome) and commit."""
        assert state in ("queued", "done")
        now = datetime.now(UTC)
        row = JobRow(
            id=uuid.uuid4().hex,
            kind=job.kind,
            state=state,
            client=job.client,
            created_at=now,
            started_at=None if state == "queued" else now,
            finished_at=None if state == "queued" else now,
            attempts=0,
            task_name=job.task_name,
            content_hash=job.content_hash,
            options_json=json.dumps(job.options, sort_keys=True),
            payload_json=json.dumps(job.payload),
            plan_id=plan_id,
            result_json=_dumps(result),
            problem_json=None,
        )
        with self._sessions() as session, session.begin():
            session.add(row)
        return _stored_job(row)

    def get_job(self, job_id: str) -> StoredJob | None:
        """The job with public id ``job_id``, or None."""
        with self._sessions() as session:
            row = session.scalars(select(JobRow).where(JobRow.id == job_id)).first()
            return None if row is None else _stored_job(row)

    def start_job(self, job_id: str) -> StoredJob | None:
        """Mark the queued job ``job_id`` running (one more attempt); None if it is not queued."""
        with self._sessions() as session, session.begin():
            changed = session.execute(
                update(JobRow)
                .where(JobRow.id == job_id, JobRow.state == "queued")
                .values(
                    state="running",
                    started_at=datetime.now(UTC),
                    attempts=JobRow.attempts + 1,
                )
            )
            if not getattr(changed, "rowcount", 0):
                return None
        return self.get_job(job_id)

    def finish_job(
        self,
        job_id: str,
        state: str,
        *,
        plan_id: str | None = None,
        result: dict[str, Any] | None = None,
        problem: dict[str, Any] | None = None,
    ) -> StoredJob | None:
        """Give the unfinished job ``job_id`` its final ``state`` and outcome.

        None if it was final already: a job cancelled as it finished keeps the first state.
        """
        assert state in JOB_STATES and state not in UNFINISHED
        with self._sessions() as session, session.begin():
            changed = session.execute(
                update(JobRow)
                .where(JobRow.id == job_id, JobRow.state.in_(UNFINISHED))
                .values(
                    state=state,
                    finished_at=datetime.now(UTC),
                    plan_id=plan_id,
                    result_json=_dumps(result),
                    problem_json=_dumps(problem),
                )
            )
            if not getattr(changed, "rowcount", 0):
                return None
        return self.get_job(job_id)

    def delete_job(self, job_id: str) -> bool:
        """Delete the job ``job_id``; False when there is none."""
        with self._sessions() as session, session.begin():
            gone = session.execute(delete(JobRow).where(JobRow.id == job_id))
        return bool(getattr(gone, "rowcount", 0))

    def recover_jobs(self, lost: dict[str, Any]) -> tuple[list[StoredJob], list[StoredJob]]:
        """At startup: jobs left ``running`` become ``lost`` with the problem ``lost``.

        Returns the jobs just marked lost and the queued jobs (oldest first) to run again.
        """
        with self._sessions() as session, session.begin():
            running = list(session.scalars(select(JobRow).where(JobRow.state == "running")))
            session.execute(
                update(JobRow)
                .where(JobRow.state == "running")
                .values(state="lost", finished_at=datetime.now(UTC), problem_json=_dumps(lost))
            )
        with self._sessions() as session:
            queued = session.scalars(
                select(JobRow).where(JobRow.state == "queued").order_by(JobRow.seq)
            )
            again = [_stored_job(r) for r in queued]
        gone = [self.get_job(r.id) for r in running]
        return [j for j in gone if j is not None], again

    def requeue_running(self) -> int:
        """At a clean shutdown: running jobs go back to the queue; how many did."""
        with self._sessions() as session, session.begin():
            changed = session.execute(
                update(JobRow)
                .where(JobRow.state == "running")
                .values(state="queued", started_at=None)
            )
        return int(getattr(changed, "rowcount", 0))


__all__ = [
    "JOB_STATES",
    "UNFINISHED",
    "JobRow",
    "NewJob",
    "NewPlan",
    "PlanRow",
    "PlanStore",
    "StoredJob",
    "StoredPlan",
    "make_engine",
]
