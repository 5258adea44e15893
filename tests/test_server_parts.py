"""Server building blocks on their own: settings, model paths, the store, the worker pool."""

from __future__ import annotations

import asyncio
import operator
import os
import signal
import sqlite3
import time
from pathlib import Path

import pytest
from _server_support import is_running
from pydantic import ValidationError

from server.db import NewJob, NewPlan, PlanStore
from server.errors import problem_for
from server.exceptions import (
    MemoryBudgetExceeded,
    ServiceBusy,
    TimeBudgetExceeded,
    WorkerFailed,
)
from server.modelpaths import resolve_model_file
from server.settings import Settings, SettingsError, settings_from_env
from server.workers import WorkerPool
from synth.exceptions import ALSyntaxError, SpecError, SynthError
from synth.models.loader import parse_task

# -- settings -------------------------------------------------------------------------------------


def test_settings_from_env(tmp_path: Path) -> None:
    settings = settings_from_env(
        {
            "SYNTH_TOKEN": "t",
            "SYNTH_DB": str(tmp_path / "x.db"),
            "SYNTH_PLAN_TIMEOUT": "2.5",
            "SYNTH_WORKERS": "3",
            "SYNTH_MODEL_DIRS": os.pathsep.join([str(tmp_path), ""]),
            "SYNTH_PROTECT_READS": "yes",
        }
    )
    assert settings.token == "t" and settings.protect_reads
    assert settings.db_url == f"sqlite:///{tmp_path / 'x.db'}"
    assert settings.plan_timeout == 2.5 and settings.workers == 3
    assert settings.model_dirs == (tmp_path.resolve(),)
    assert settings_from_env({"SYNTH_DB": "postgresql://u@h/db"}).db_url == "postgresql://u@h/db"
    assert settings_from_env({"SYNTH_TOKEN": ""}).token is None


@pytest.mark.parametrize(
    ("env", "message"),
    [
        ({"SYNTH_WORKERS": "many"}, "SYNTH_WORKERS='many': Input should be a valid integer"),
        ({"SYNTH_WORKERS": "0"}, "SYNTH_WORKERS='0': Input should be greater than or equal to 1"),
        ({"SYNTH_PLAN_TIMEOUT": "-1"}, "SYNTH_PLAN_TIMEOUT='-1': Input should be greater than 0"),
        ({"SYNTH_DB": ""}, "SYNTH_DB='': String should have at least 1 character"),
        ({"SYNTH_PROTECT_READS": "maybe"}, "SYNTH_PROTECT_READS='maybe': Input should be a valid"),
        ({"SYNTH_TRIALS": "300"}, "the default trials (300, SYNTH_TRIALS) exceed the maximum"),
    ],
)
def test_bad_settings_name_the_variable(env: dict[str, str], message: str) -> None:
    with pytest.raises(SettingsError) as info:
        settings_from_env(env)
    assert isinstance(info.value, ValueError)  # what `synth serve` reports as a usage error
    assert str(info.value).startswith(message)


def test_settings_come_from_the_environment_only_when_asked(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("SYNTH_TOKEN", "from-the-shell")
    monkeypatch.setenv("SYNTH_MAX_TRIALS", "50")
    assert Settings().token is None  # a test's (or a caller's) settings ignore the shell
    from_env = settings_from_env()
    assert from_env.token == "from-the-shell" and from_env.max_trials == 50
    # The CLI's flags over the environment: validated and normalised like the environment.
    changed = from_env.with_(db_url="relative.db", model_dirs=("/tmp/../tmp",))
    assert changed.db_url.startswith("sqlite:////") and changed.model_dirs == (Path("/tmp"),)
    with pytest.raises(SettingsError, match="SYNTH_WORKERS=0"):
        from_env.with_(workers=0)
    with pytest.raises(ValidationError):  # frozen
        from_env.workers = 3  # type: ignore[misc]


# -- model paths ----------------------------------------------------------------------------------


@pytest.fixture
def models(tmp_path: Path) -> Path:
    root = tmp_path / "models"
    (root / "ur5" / "meshes").mkdir(parents=True)
    (root / "ur5" / "ur5.urdf").write_text("<robot name='ur5'/>")
    (tmp_path / "outside.urdf").write_text("<robot name='x'/>")
    os.symlink(tmp_path / "outside.urdf", root / "escape.urdf")
    os.symlink(root / "ur5" / "ur5.urdf", root / "inside.urdf")
    return root


def test_model_files_resolve_inside_model_dirs(models: Path) -> None:
    found = resolve_model_file("ur5/ur5.urdf", "f", [models])
    assert found == (models / "ur5" / "ur5.urdf").resolve()
    assert resolve_model_file(str(found), "f", [models]) == found
    assert resolve_model_file("inside.urdf", "f", [models]) == found  # symlink that stays in
    meshes = resolve_model_file("ur5/meshes", "f", [models], directory=True)
    assert meshes.is_dir()


@pytest.mark.parametrize(
    ("reference", "fragment"),
    [
        ("../outside.urdf", "'..'"),
        ("ur5/../../outside.urdf", "'..'"),
        ("escape.urdf", "symlink"),
        ("/etc/passwd", "inside a model directory"),
        ("missing.urdf", "not in the server's model directories"),
        ("ur5/meshes", "not a file"),
        ("", "not a valid path"),
    ],
)
def test_model_file_escapes_are_spec_errors(models: Path, reference: str, fragment: str) -> None:
    with pytest.raises(SpecError) as info:
        resolve_model_file(reference, "manipulator.arm.urdf", [models])
    assert info.value.path == "manipulator.arm.urdf"
    assert fragment in info.value.detail


def test_no_model_dirs_means_no_model_files() -> None:
    with pytest.raises(SpecError, match="no model directories"):
        resolve_model_file("ur5.urdf", "f", [])


# -- store ----------------------------------------------------------------------------------------


def _plan(key: str) -> NewPlan:
    return NewPlan(
        content_hash=key,
        task_name="t",
        spec_text="name: t\n",
        spec_media_type="yaml",
        spec={"name": "t"},
        options={"trials": 1},
        result={"strategy": {"name": "s"}},
        program="BEGIN END\n",
        validation={"success_rate": 1.0},
    )


def test_store_uses_wal_and_deduplicates(tmp_path: Path) -> None:
    db = tmp_path / "plans.db"
    store = PlanStore(f"sqlite:///{db}")
    store.create_schema()
    first, created = store.add(_plan("k1"))
    twin, again = store.add(_plan("k1"))
    assert created and not again and twin.id == first.id
    store.close()
    with sqlite3.connect(db) as raw:
        assert raw.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    reopened = PlanStore(f"sqlite:///{db}")
    got = reopened.get(first.id)
    assert got is not None and got.validation == {"success_rate": 1.0}
    assert got.created_at.tzinfo is not None
    assert reopened.get("nope") is None
    reopened.close()


def test_store_pages(tmp_path: Path) -> None:
    store = PlanStore("sqlite://")
    store.create_schema()
    ids = [store.add(_plan(f"k{i}"))[0].id for i in range(5)]
    page, cursor = store.page(3)
    assert [p.id for p in page] == ids[:1:-1] and cursor is not None
    rest, end = store.page(3, cursor)
    assert [p.id for p in rest] == ids[1::-1] and end is None


def _job(client: str = "c") -> NewJob:
    return NewJob("replay", client, "t", None, {"trials": 1}, {"program": "BEGIN END"})


def test_store_keeps_a_jobs_lifecycle_and_its_first_final_state(tmp_path: Path) -> None:
    store = PlanStore(f"sqlite:///{tmp_path / 'jobs.db'}")
    store.create_schema()
    job = store.add_job(_job())
    assert job.state == "queued" and job.attempts == 0 and not job.finished
    started = store.start_job(job.id)
    assert started is not None and started.state == "running" and started.attempts == 1
    assert started.started_at is not None and started.started_at.tzinfo is not None
    assert store.start_job(job.id) is None  # only a queued job starts
    ended = store.finish_job(job.id, "cancelled", problem={"status": 409})
    assert ended is not None and ended.finished and ended.problem == {"status": 409}
    # A job that finishes as it is cancelled keeps the first final state.
    assert store.finish_job(job.id, "done", result={"ok": True}) is None
    kept = store.get_job(job.id)
    assert kept is not None and kept.state == "cancelled" and kept.result is None
    assert store.delete_job(job.id) and store.get_job(job.id) is None
    assert not store.delete_job(job.id)
    plan, _ = store.add(_plan("k"))
    assert store.delete_plan(plan.id) and store.get(plan.id) is None
    assert not store.delete_plan(plan.id)
    store.close()


def test_store_recovers_jobs_after_a_crash_and_after_a_clean_stop(tmp_path: Path) -> None:
    store = PlanStore(f"sqlite:///{tmp_path / 'jobs.db'}")
    store.create_schema()
    was_running = store.add_job(_job("a"))
    store.start_job(was_running.id)
    first, second = store.add_job(_job("b")), store.add_job(_job("c"))
    done = store.add_job(_job("d"), state="done", result={"ok": True})
    lost, queued = store.recover_jobs({"title": "Job lost", "status": 503})
    assert [j.id for j in lost] == [was_running.id]
    assert lost[0].state == "lost" and lost[0].problem == {"title": "Job lost", "status": 503}
    assert [j.id for j in queued] == [first.id, second.id]  # oldest first
    assert [j.client for j in queued] == ["b", "c"]
    kept = store.get_job(done.id)
    assert kept is not None and kept.state == "done"
    store.start_job(first.id)
    assert store.requeue_running() == 1  # a clean stop: running goes back to the queue
    back = store.get_job(first.id)
    assert back is not None and back.state == "queued" and back.started_at is None
    assert back.attempts == 1  # the run it started is still counted
    store.close()


# -- the one error mapping ------------------------------------------------------------------------


def test_problem_for_maps_synth_errors_to_422_with_fields() -> None:
    status, body, _ = problem_for(SpecError("frames[1].pose", "bad pose", 7))
    assert status == 422 and body["path"] == "frames[1].pose" and body["line"] == 7
    status, body, _ = problem_for(
        ALSyntaxError(3, 5, "unexpected token", expected=("THEN",), hint="h")
    )
    assert status == 422 and body["column"] == 5 and body["expected"] == ["THEN"]
    status, body, _ = problem_for(SynthError("anything a user can cause"))
    assert status == 422
    status, body, _ = problem_for(KeyError("bug"))
    assert status == 500 and "bug" not in body["detail"]


# -- worker pool ----------------------------------------------------------------------------------


def test_worker_pool_budget_busy_bugs_and_crashes() -> None:
    async def scenario() -> None:
        pool = WorkerPool(1)
        await pool.start()
        try:
            assert await pool.run(operator.add, 2, 3, timeout=30, what="adding") == 5
            # A SynthError comes back as the same class with the same fields.
            with pytest.raises(SpecError) as info:
                await pool.run(parse_task, "name: t\nframes: []\n", timeout=30, what="parsing")
            assert info.value.path == "frames" and info.value.line == 2
            assert str(info.value) == "frames (line 2): a task needs at least one frame"
            # Any other exception is a bug: WorkerFailed with the remote traceback.
            with pytest.raises(WorkerFailed) as bug:
                await pool.run(operator.truediv, 1, 0, timeout=30, what="dividing")
            assert "ZeroDivisionError" in bug.value.remote_traceback
            # Overrun: the worker is killed, the caller told at once.
            started = time.monotonic()
            with pytest.raises(TimeBudgetExceeded):
                await pool.run(time.sleep, 30, timeout=0.5, what="sleeping")
            assert time.monotonic() - started < 5
            assert pool.jobs_killed == 1
            # A job queued behind a long one gives up when its wait exceeds the budget: 503.
            slow = asyncio.ensure_future(pool.run(time.sleep, 1.0, timeout=60, what="sleeping"))
            await asyncio.sleep(0)  # the long job queues first
            with pytest.raises(ServiceBusy):
                await pool.run(operator.add, 1, 1, timeout=0.2, what="adding")
            await slow
            # With its own wait, a job that got a worker late still has its whole budget.
            slow = asyncio.ensure_future(pool.run(time.sleep, 0.6, timeout=60, what="sleeping"))
            await asyncio.sleep(0)
            assert await pool.run(time.sleep, 0.3, timeout=0.5, wait=5, what="sleeping") is None
            await slow
            # A worker that dies mid-job is a bug (500) and is replaced.
            with pytest.raises(WorkerFailed, match=r"died during exiting \(exit code 3\)"):
                await pool.run(os._exit, 3, timeout=30, what="exiting")
            assert await pool.run(operator.mul, 6, 7, timeout=30, what="multiplying") == 42
        finally:
            await pool.close()
        assert pool.alive == 0

    asyncio.run(scenario())


# Evaluated in a worker: its parent's pid, its own, and whether synth's planner was imported
# before the job.
ABOUT_THE_WORKER = (
    "(__import__('os').getppid(), __import__('os').getpid(),"
    " 'synth.pipeline' in __import__('sys').modules)"
)


def test_workers_are_forks_of_one_warmed_zygote_and_die_with_it() -> None:
    """Two pools with the server's warm-up share this process's zygote: their workers are its
    children, with synth imported before their first job (a fresh interpreter has not imported
    it, as the layer checks show). Killing the zygote kills its workers (PR_SET_PDEATHSIG); the
    pool replaces the dead idle worker from a new zygote, and the job runs there."""
    warm = "server.service:warm_up"

    async def scenario() -> None:
        first, second = WorkerPool(1, warmup=warm), WorkerPool(1, warmup=warm)
        await first.start()
        await second.start()
        try:
            zygote, a, warm_a = await first.run(eval, ABOUT_THE_WORKER, timeout=60, what="asking")
            parent, b, warm_b = await second.run(eval, ABOUT_THE_WORKER, timeout=60, what="asking")
            assert zygote == parent != os.getpid() and a != b and warm_a and warm_b
            os.kill(zygote, signal.SIGKILL)
            deadline = time.monotonic() + 10
            while (is_running(a) or is_running(b)) and time.monotonic() < deadline:
                await asyncio.sleep(0.05)
            assert not is_running(a) and not is_running(b)
            assert first.alive == second.alive == 0
            again, c, warm_c = await first.run(eval, ABOUT_THE_WORKER, timeout=60, what="asking")
            assert warm_c and again not in (zygote, os.getpid()) and c not in (a, b)
        finally:
            await first.close()
            await second.close()
        assert first.alive == second.alive == 0

    asyncio.run(scenario())


def test_serve_refuses_a_database_it_cannot_open(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from server.serve import serve

    assert serve(db=str(tmp_path / "missing" / "x.db"), port=0) == 2
    assert "cannot open the database" in capsys.readouterr().err
    assert serve(db="postgresql://u:secret@127.0.0.1:1/x", port=0) == 2
    assert "secret" not in capsys.readouterr().err


def test_a_job_over_the_memory_cap_is_refused_and_its_worker_replaced() -> None:
    async def scenario() -> None:
        pool = WorkerPool(1, memory_limit=1 << 30)
        await pool.start()
        try:
            with pytest.raises(MemoryBudgetExceeded) as info:
                await pool.run(bytearray, 1 << 34, timeout=30, what="allocating")
            assert info.value.status == 422 and info.value.extra["limit_mib"] == 1024
            assert await pool.run(operator.add, 1, 2, timeout=30, what="adding") == 3
        finally:
            await pool.close()

    asyncio.run(scenario())
