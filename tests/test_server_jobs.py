"""The job flow of the service: submit (202 + the job's URL), poll or wait, batches, DELETE.

One app with one worker serves the module. A "long" job is a replay of the seed's golden
program with the server's maximum of trials (200, about 12 s): the tests cancel it rather than
wait for it. The restart rules (lost, queued again) are tested on a real server process in
``test_server_process.py``.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import pytest
import yaml
from _paths import ROOT, SEED_TASK
from _server_support import FINAL, YAML, client_for, done, finished, overridden
from fastapi.testclient import TestClient

from server.settings import Settings

SEED_TEXT = SEED_TASK.read_text()
GOLDEN = (ROOT / "fixtures" / "golden" / "seed_4_8.al").read_text()
LONG = {"program": GOLDEN, "spec": SEED_TEXT, "trials": 200}
QUICK = {"program": GOLDEN, "spec": SEED_TEXT, "trials": 0}


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    db = tmp_path_factory.mktemp("jobs") / "jobs.db"
    with client_for(Settings(db_url=str(db), workers=1, plan_timeout=120.0)) as c:
        yield c


def problem(response: Any, status: int) -> dict[str, Any]:
    assert response.status_code == status, response.text
    assert response.headers["content-type"].startswith("application/problem+json")
    body = response.json()
    assert body["status"] == status and body["title"] and body["detail"]
    return dict(body)


def running(client: TestClient, location: str, timeout: float = 60.0) -> dict[str, Any]:
    """The job at ``location`` once it is running (bounded)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        job = client.get(location).json()
        if job["state"] != "queued":
            assert job["state"] == "running", job
            return dict(job)
        time.sleep(0.05)
    raise AssertionError(f"{location} did not start within {timeout:g} s")


def cancel(client: TestClient, location: str) -> dict[str, Any]:
    answer = client.delete(location)
    assert answer.status_code == 200, answer.text
    job = answer.json()
    assert job["state"] == "cancelled", job
    return dict(job)


# -- the flow -----------------------------------------------------------------------------------


def test_a_long_job_does_not_block_the_service(client: TestClient) -> None:
    started = time.monotonic()
    submitted = client.post("/v1/replays", json=LONG)
    assert time.monotonic() - started < 2.0  # answered at once, not after the 200 trials
    assert submitted.status_code == 202, submitted.text
    job = submitted.json()
    location = submitted.headers["location"]
    assert location == f"/v1/jobs/{job['id']}" == job["links"]["self"]
    assert submitted.headers["retry-after"] == "1"
    assert job["kind"] == "replay" and job["state"] in ("queued", "running")
    assert job["task"] == "seed_4_8" and job["options"]["trials"] == 200
    assert job["result"] is None and job["problem"] is None and job["finished_at"] is None
    now = running(client, location)
    assert now["attempts"] == 1 and now["started_at"] >= now["created_at"]
    # While it runs the service answers: health, reads, and a bounded long poll.
    assert client.get("/healthz").json()["jobs"]["running"] == 1
    t0 = time.monotonic()
    polled = client.get(f"{location}?wait=0.3")
    assert 0.25 < time.monotonic() - t0 < 5.0
    assert polled.json()["state"] == "running" and polled.headers["retry-after"] == "1"
    # Another submission is accepted at once, and queued behind it (one worker, one lane).
    second = client.post("/v1/replays", json=QUICK)
    assert second.status_code == 202 and second.json()["state"] == "queued"
    cancel(client, location)
    report = done(client, second)
    assert report["nominal"]["outcome"] == "success" and report["monte_carlo"]["trials"] == 0
    job = client.get(second.headers["location"]).json()
    assert job["created_at"] <= job["started_at"] <= job["finished_at"]
    assert "retry-after" not in client.get(second.headers["location"]).headers


def test_a_submission_can_wait_for_its_job(client: TestClient) -> None:
    answer = client.post("/v1/replays?wait=30", json=QUICK)
    assert answer.status_code == 201, answer.text  # finished within the wait: final at once
    assert answer.headers["location"] == f"/v1/jobs/{answer.json()['id']}"
    assert answer.json()["state"] == "done" and answer.json()["result"]["ok"] is True


@pytest.mark.parametrize("wait", ["31", "1e9"])
def test_a_wait_over_the_servers_maximum_is_422_naming_it(client: TestClient, wait: str) -> None:
    body = problem(client.get(f"/v1/jobs/{'0' * 32}?wait={wait}"), 422)
    assert body["parameter"] == "wait" and body["maximum"] == 30
    body = problem(client.post(f"/v1/replays?wait={wait}", json=QUICK), 422)
    assert body["parameter"] == "wait"
    problem(client.get(f"/v1/jobs/{'0' * 32}?wait=-1"), 422)


def test_the_trial_limit_is_a_setting_and_names_the_field(client: TestClient) -> None:
    app = client.app
    with overridden(app, max_trials=3, default_trials=2):  # type: ignore[arg-type]
        for answer in (
            client.post("/v1/plans?trials=4", content=SEED_TEXT, headers=YAML),
            client.post("/v1/replays", json={**QUICK, "trials": 4}),
        ):
            body = problem(answer, 422)
            assert body["parameter"] == "trials" and body["maximum"] == 3
            assert "SYNTH_MAX_TRIALS" in body["detail"]
        accepted = client.post("/v1/replays", json={**QUICK, "trials": 3})
        assert accepted.status_code == 202
        defaulted = client.post("/v1/replays", json={"program": GOLDEN, "spec": SEED_TEXT})
        assert defaulted.json()["options"]["trials"] == 2
    assert done(client, accepted)["monte_carlo"]["trials"] == 3
    assert done(client, defaulted)["monte_carlo"]["trials"] == 2


def test_the_server_refuses_jobs_beyond_its_limit_with_503(client: TestClient) -> None:
    first = client.post("/v1/replays", json=LONG)
    with overridden(client.app, max_jobs=1):  # type: ignore[arg-type]
        body = problem(client.post("/v1/replays", json=QUICK), 503)
    assert "SYNTH_MAX_JOBS" in body["detail"]
    cancel(client, first.headers["location"])


# -- DELETE -------------------------------------------------------------------------------------


def test_deleting_a_running_job_cancels_it_and_stops_its_worker(client: TestClient) -> None:
    submitted = client.post("/v1/replays", json=LONG)
    location = submitted.headers["location"]
    running(client, location)
    pool = client.app.state.service.pool  # type: ignore[attr-defined]
    runs_before = pool.jobs_run
    started = time.monotonic()
    job = cancel(client, location)
    assert time.monotonic() - started < 5.0  # not after the replay's 12 s
    assert job["problem"]["status"] == 409 and job["problem"]["title"] == "Job cancelled"
    assert job["finished_at"] is not None and job["result"] is None
    assert pool.jobs_run == runs_before  # the replay never completed in its worker
    # The worker was replaced: the next job runs.
    assert done(client, client.post("/v1/replays", json=QUICK))["ok"] is True
    # A cancelled job is final: DELETE now removes its record.
    assert client.delete(location).status_code == 204
    problem(client.get(location), 404)
    problem(client.delete(location), 404)


def test_deleting_a_queued_job_cancels_it_before_it_runs(client: TestClient) -> None:
    first = client.post("/v1/replays", json=LONG)
    queued = client.post("/v1/replays", json=QUICK)
    assert queued.json()["state"] == "queued"
    job = cancel(client, queued.headers["location"])
    assert job["attempts"] == 0 and job["started_at"] is None
    cancel(client, first.headers["location"])
    after = client.get(queued.headers["location"]).json()
    assert after["state"] == "cancelled" and after["attempts"] == 0  # it never ran
    assert client.get("/healthz").json()["jobs"] == {"unfinished": 0, "running": 0, "queued": 0}


def test_deleting_a_plan_leaves_its_job_and_a_resubmission_plans_again(
    client: TestClient,
) -> None:
    first = client.post("/v1/plans?validate=false", content=SEED_TEXT, headers=YAML)
    plan = done(client, first)
    job = client.get(first.headers["location"]).json()
    assert job["plan_id"] == plan["id"] and job["reused"] is False
    assert job["links"]["plan"] == plan["links"]["self"]
    assert client.delete(plan["links"]["self"]).status_code == 204
    problem(client.get(plan["links"]["self"]), 404)
    problem(client.delete(plan["links"]["self"]), 404)
    problem(client.get(plan["links"]["program"]), 404)
    after = client.get(first.headers["location"]).json()
    assert after["state"] == "done" and after["plan_id"] == plan["id"] and after["result"] is None
    again = client.post("/v1/plans?validate=false", content=SEED_TEXT, headers=YAML)
    assert again.status_code == 202  # not answered from the store: the plan is gone
    replanned = done(client, again)
    assert replanned["id"] != plan["id"] and replanned["program"] == plan["program"]
    # A finished job's DELETE removes the job only; its plan stays.
    assert client.delete(again.headers["location"]).status_code == 204
    assert client.get(replanned["links"]["self"]).status_code == 200


# -- batches ------------------------------------------------------------------------------------


def test_a_batch_answers_each_task_and_keeps_the_good_ones(client: TestClient) -> None:
    tasks: list[Any] = [
        {"spec": SEED_TEXT + "# batch\n", "validate": False},  # new bytes: not reused
        {"spec": "name: t\nframes: []\n"},
        {"spec": SEED_TEXT, "trials": 10**6},
        42,
        {"spec": yaml.safe_load(SEED_TEXT), "validate": False, "try_harder": True},
        {"spec": SEED_TEXT, "colour": "red"},
    ]
    answer = client.post("/v1/plans/batch", json={"tasks": tasks})
    assert answer.status_code == 202, answer.text
    batch = answer.json()
    assert batch["accepted"] == 2 and batch["rejected"] == 4
    items = batch["items"]
    assert [item["index"] for item in items] == list(range(len(tasks)))
    assert [item["status"] for item in items] == [202, 422, 422, 422, 202, 422]
    assert items[1]["problem"]["path"] == "frames"
    assert items[2]["problem"]["parameter"] == "tasks[2].trials"
    assert items[3]["problem"]["errors"][0]["loc"][:2] == ["tasks", 3]
    assert items[5]["problem"]["errors"][0]["loc"] == ["tasks", 5, "colour"]
    for item in (items[0], items[4]):
        assert item["location"] == f"/v1/jobs/{item['job']['id']}"
        assert item["job"]["state"] in ("queued", "running") and item["problem"] is None
        job = finished(client, client.get(item["location"]))
        assert job["state"] == "done" and job["result"]["task"] == "seed_4_8"
    options = [finished(client, client.get(i["location"]))["options"] for i in (items[0], items[4])]
    assert [o["try_harder"] for o in options] == [False, True]


def test_a_batch_of_reused_plans_is_done_at_once(client: TestClient) -> None:
    plan = done(client, client.post("/v1/plans?validate=false", content=SEED_TEXT, headers=YAML))
    task = {"spec": SEED_TEXT, "validate": False}
    answer = client.post("/v1/plans/batch", json={"tasks": [task]})
    item = answer.json()["items"][0]
    assert answer.status_code == 202 and item["status"] == 201
    assert item["job"]["state"] == "done" and item["job"]["reused"] is True
    assert item["job"]["result"]["id"] == plan["id"]


def test_a_batch_with_no_good_task_is_a_problem_listing_each(client: TestClient) -> None:
    answer = client.post("/v1/plans/batch", json={"tasks": [{"spec": "name: t\n"}, {"x": 1}]})
    body = problem(answer, 422)
    assert body["accepted"] == 0 and body["rejected"] == 2
    assert [item["status"] for item in body["items"]] == [422, 422]
    assert body["items"][0]["problem"]["path"] == "frames"


def test_a_batch_over_the_servers_maximum_or_empty_is_422(client: TestClient) -> None:
    with overridden(client.app, max_batch=2):  # type: ignore[arg-type]
        body = problem(
            client.post("/v1/plans/batch", json={"tasks": [{"spec": SEED_TEXT}] * 3}), 422
        )
    assert body["parameter"] == "tasks" and body["maximum"] == 2
    problem(client.post("/v1/plans/batch", json={"tasks": []}), 422)
    problem(client.post("/v1/plans/batch", json=[{"spec": SEED_TEXT}]), 422)


def test_a_batch_past_the_clients_queue_refuses_the_rest_with_429(tmp_path: Any) -> None:
    settings = Settings(db_url=str(tmp_path / "q.db"), workers=1, queue_per_client=1)
    with client_for(settings) as small:
        tasks = [{"spec": SEED_TEXT, "seed": s, "trials": 1} for s in range(4)]
        answer = small.post("/v1/plans/batch", json={"tasks": tasks})
        assert answer.status_code == 202, answer.text
        statuses = [item["status"] for item in answer.json()["items"]]
        assert statuses == [202, 202, 429, 429]  # one runs, one waits, the rest are refused
        assert answer.json()["items"][2]["problem"]["running"] == 1
        for item in answer.json()["items"][:2]:
            small.delete(item["location"])
        assert all(
            small.get(i["location"]).json()["state"] in FINAL for i in answer.json()["items"][:2]
        )


@pytest.mark.parametrize("wait", ["nan", "inf"])
def test_a_wait_that_is_not_a_finite_number_is_422_saying_so(client: TestClient, wait: str) -> None:
    # NaN compares false with everything: it was refused as "not ≥ 0", a negative number
    body = problem(client.get(f"/v1/jobs/{'0' * 32}?wait={wait}"), 422)
    errors = body["errors"]
    assert isinstance(errors, list) and len(errors) == 1, errors
    assert errors[0]["loc"] == ["query", "wait"]
    assert errors[0]["msg"] == "Input should be a finite number", errors
