"""HTTP API through FastAPI's TestClient: every endpoint and every error status.

One app (one worker process) serves the module; tests that need other settings override
``get_settings`` for their duration, the way the style guide's FastAPI tutorial does. Plans and
replays are jobs: a submission is answered 202 and followed to its end (``_server_support``);
the job flow itself (waiting, batches, DELETE, restarts) is in ``test_server_jobs.py`` and
``test_server_process.py``.
"""

from __future__ import annotations

import json
import logging
import os
import re
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml
from _paths import SEED_TASK
from _server_support import YAML, client_for, done, failed, overridden
from fastapi.testclient import TestClient

from server.db import NewPlan
from server.settings import Settings

SEED_TEXT = SEED_TASK.read_text()


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    db = tmp_path_factory.mktemp("db") / "plans.db"
    with client_for(Settings(db_url=str(db), workers=1, plan_timeout=60.0)) as c:
        yield c


def problem(response: object, status: int) -> dict[str, object]:
    assert getattr(response, "status_code", None) == status, getattr(response, "text", "")
    headers = getattr(response, "headers", {})
    assert headers["content-type"].startswith("application/problem+json")
    body = response.json()  # type: ignore[attr-defined]
    assert body["status"] == status
    assert body["title"] and body["detail"] and body["type"]
    return dict(body)


# -- health and schema ----------------------------------------------------------------------------


def test_healthz_reports_database_workers_and_jobs(client: TestClient) -> None:
    body = client.get("/healthz").json()
    assert body["status"] == "ok"
    assert body["database"] == "ok"
    assert body["workers"]["size"] == 1 and body["workers"]["alive"] == 1
    assert set(body["jobs"]) == {"unfinished", "running", "queued"}
    assert "stages" not in body  # every stage is part of the build: nothing to probe


def test_openapi_documents_every_endpoint(client: TestClient) -> None:
    schema = client.get("/openapi.json").json()
    paths = schema["paths"]
    assert set(paths) >= {
        "/healthz",
        "/v1/plans",
        "/v1/plans/{plan_id}",
        "/v1/plans/{plan_id}/program.al",
        "/v1/plans/batch",
        "/v1/replays",
        "/v1/jobs/{job_id}",
    }
    body = paths["/v1/plans"]["post"]["requestBody"]["content"]
    assert {"application/yaml", "application/json"} <= set(body)
    for path in ("/v1/plans", "/v1/replays", "/v1/plans/batch"):
        responses = paths[path]["post"]["responses"]
        assert {"202", "422"} <= set(responses), path
    assert {"get", "delete"} <= set(paths["/v1/jobs/{job_id}"])
    assert "delete" in paths["/v1/plans/{plan_id}"]
    assert "HTTPBearer" in json.dumps(schema["components"]["securitySchemes"])


# -- spec errors: 422 with the field path and line ------------------------------------------------


def test_spec_error_names_field_and_yaml_line(client: TestClient) -> None:
    text = SEED_TEXT.replace("[45.2 cm, 102 cm, 0 cm]", "[45.2, 102 cm, 0 cm]", 1)
    line = next(i for i, s in enumerate(text.splitlines(), 1) if "[45.2, 102 cm" in s)
    body = problem(client.post("/v1/plans", content=text, headers=YAML), 422)
    assert body["path"] == "frames[0].pose.translation[0]"
    assert body["line"] == line
    assert "unit" in str(body["message"])


def test_json_spec_error_names_field(client: TestClient) -> None:
    data = yaml.safe_load(SEED_TEXT)
    data["insertion"]["dr_ok"] = "3 kg"
    body = problem(client.post("/v1/plans", json=data), 422)
    assert body["path"] == "insertion.dr_ok"


def test_a_json_key_given_twice_is_refused_as_in_yaml(client: TestClient) -> None:
    # json.loads keeps the last of two keys: a second "insertion" into BH2 was planned (201)
    # where the same YAML is a 422 naming the key
    data = yaml.safe_load(SEED_TEXT)
    text = json.dumps(data)
    second = json.dumps({"pin": "PIN1", "hole": "BH2", "start_hole": "RH1"})
    twice = text[:-1] + f', "insertion": {second}}}'
    assert json.loads(twice)["insertion"]["hole"] == "BH2"  # the silent last-wins
    body = problem(
        client.post(
            "/v1/plans?validate=false",
            content=twice.encode("utf-8"),
            headers={"Content-Type": "application/json"},
        ),
        422,
    )
    assert body["path"] == "insertion"
    assert "the key 'insertion' is given twice" in str(body["detail"])


def test_json_syntax_error_has_line(client: TestClient) -> None:
    body = problem(
        client.post(
            "/v1/plans",
            content=b'{"name": "t",\n "frames": [}',
            headers={"Content-Type": "application/json"},
        ),
        422,
    )
    assert body["line"] == 2 and "JSON" in str(body["detail"])


@pytest.mark.parametrize(
    ("body", "fragment"),
    [
        (b"", "empty"),
        (b"\xff\xfe name: t", "UTF-8"),
        (b"a: &x [1, 2]\nb: *x\n", "alias"),
        (b"[" * 100 + b"]" * 100, "nested"),
        (b"- just\n- a list\n", "mapping"),
        (b"name: t\nframes: [\n", "YAML syntax"),
    ],
)
def test_malformed_bodies_are_422(client: TestClient, body: bytes, fragment: str) -> None:
    answer = problem(client.post("/v1/plans", content=body, headers=YAML), 422)
    assert fragment.lower() in str(answer["detail"]).lower()


def test_unsupported_media_type_is_415(client: TestClient) -> None:
    answer = problem(client.post("/v1/plans", data={"spec": SEED_TEXT}), 415)
    assert "application/yaml" in answer["accepted"]  # type: ignore[operator]
    # The JSON routes too (a form post was a 422 "Input should be a valid dictionary")
    for path in ("/v1/replays", "/v1/plans/batch"):
        answer = problem(client.post(path, data={"spec": SEED_TEXT}), 415)
        assert answer["accepted"] == ["application/json"]
        plain = client.post(path, content=b"{}", headers={"Content-Type": "text/plain"})
        problem(plain, 415)
    schema = client.get("/openapi.json").json()
    assert "415" in schema["paths"]["/v1/replays"]["post"]["responses"]
    assert "415" in schema["paths"]["/v1/plans/batch"]["post"]["responses"]


@pytest.mark.parametrize(
    ("path", "name", "near"),
    [
        ("/v1/plans?trails=5&validate=false", "trails", "trials"),
        ("/v1/plans?limt=5", "limt", "limit"),
        ("/healthz?verbose=1", "verbose", None),
    ],
)
def test_unknown_query_parameter_is_named(
    client: TestClient, path: str, name: str, near: str | None
) -> None:
    # Ignored, a typo planned with the server's default trials and said nothing
    method = client.post if path.startswith("/v1/plans?t") else client.get
    kwargs = {"content": SEED_TEXT, "headers": YAML} if method == client.post else {}
    answer = problem(method(path, **kwargs), 422)  # type: ignore[operator]
    assert answer["parameter"] == name
    assert (f"did you mean {near!r}" in str(answer["detail"])) == (near is not None)
    assert client.get("/v1/plans?limit=5").status_code == 200  # the route's own still work


def test_a_repeated_query_parameter_is_refused(client: TestClient) -> None:
    # ?trials=3&trials=5 planned with 5 trials and said nothing (the fourth hunt, item c);
    # nothing is stored: the listing is as it was
    before = client.get("/v1/plans").json()
    answer = problem(
        client.post("/v1/plans?trials=3&trials=5", content=SEED_TEXT, headers=YAML), 422
    )
    assert answer["parameter"] == "trials"
    assert "'trials' is given 2 times ('3', '5'); give it once" in str(answer["detail"])
    assert client.get("/v1/plans").json() == before
    problem(client.get("/v1/plans?limit=5&limit=5"), 422)


@pytest.mark.parametrize(
    ("field", "value"), [("trials", True), ("trials", "3"), ("seed", 1.0), ("seed", False)]
)
def test_json_numbers_are_numbers(client: TestClient, field: str, value: object) -> None:
    # JSON true was one trial, "3" three: a JSON body's integers are JSON integers
    replay = {"program": "BEGIN END", "spec": SEED_TEXT, field: value}
    answer = problem(client.post("/v1/replays", json=replay), 422)
    assert str(answer["detail"]).startswith(f"body.{field}: ")
    batch = {"tasks": [{"spec": SEED_TEXT, field: value}]}
    item = problem(client.post("/v1/plans/batch", json=batch), 422)["items"][0]  # type: ignore[index]
    assert item["problem"]["errors"][0]["loc"] == ["tasks", 0, field]


@pytest.mark.parametrize(("value", "kind"), [(5, "a number"), ([1], "an array"), (None, "null")])
def test_a_spec_of_the_wrong_type_is_one_error(
    client: TestClient, value: object, kind: str
) -> None:
    # Left to pydantic's union it was two errors under its branch names (spec.dict[str,any])
    batch = {"tasks": [{"spec": value}]}
    item = problem(client.post("/v1/plans/batch", json=batch), 422)["items"][0]  # type: ignore[index]
    assert item["problem"]["errors"] == [
        {
            "loc": ["tasks", 0, "spec"],
            "msg": f"a task spec is YAML text or a JSON object, not {kind}",
        }
    ]
    if value is not None:  # a replay's spec may be null (then plan_id is needed)
        replay = {"program": "BEGIN END", "spec": value}
        answer = problem(client.post("/v1/replays", json=replay), 422)
        assert (
            answer["detail"] == f"body.spec: a task spec is YAML text or a JSON object, not {kind}"
        )


def test_a_json_body_that_is_not_utf8_says_so(client: TestClient) -> None:
    # FastAPI's own answer was "There was an error parsing the body"
    body = b'{"program": "\xff", "spec": "x"}'
    answer = problem(
        client.post("/v1/replays", content=body, headers={"Content-Type": "application/json"}),
        400,
    )
    assert (
        answer["detail"]
        == f"the body is not UTF-8 text (byte {body.index(0xFF)}): send JSON as UTF-8"
    )


# -- model files stay inside the model directories ------------------------------------------------


def _urdf_spec(urdf: str) -> str:
    return SEED_TEXT.replace(
        "    model: stanford", f"    urdf: {json.dumps(urdf)}\n    tool_frame: tool0", 1
    )


def test_urdf_reference_is_refused_without_model_dirs(client: TestClient) -> None:
    text = _urdf_spec("arm.urdf")
    body = problem(client.post("/v1/plans", content=text, headers=YAML), 422)
    assert body["path"] == "manipulator.arm.urdf"
    assert "model directories" in str(body["detail"])
    # the field's line in the posted YAML, as every spec refusal gives (it was null)
    line = next(n for n, t in enumerate(text.splitlines(), 1) if t.strip().startswith("urdf:"))
    assert body["line"] == line


@pytest.mark.parametrize("reference", ["../secret.urdf", "/etc/passwd", "link.urdf"])
def test_urdf_reference_cannot_escape_model_dir(
    client: TestClient, tmp_path: Path, reference: str
) -> None:
    models = tmp_path / "models"
    models.mkdir()
    (tmp_path / "secret.urdf").write_text("<robot name='x'/>")
    os.symlink(tmp_path / "secret.urdf", models / "link.urdf")
    with overridden(client.app, model_dirs=(models,)):  # type: ignore[arg-type]
        body = problem(client.post("/v1/plans", content=_urdf_spec(reference), headers=YAML), 422)
    assert body["path"] == "manipulator.arm.urdf"


# -- limits ---------------------------------------------------------------------------------------


def test_body_over_limit_is_413(client: TestClient) -> None:
    with overridden(client.app, max_body_bytes=1000):  # type: ignore[arg-type]
        body = problem(client.post("/v1/plans", content=b"#" * 1001, headers=YAML), 413)
        assert body["limit_bytes"] == 1000

        def chunks() -> Iterator[bytes]:  # no Content-Length: read up to the limit
            for _ in range(20):
                yield b"#" * 100

        problem(client.post("/v1/plans", content=chunks(), headers=YAML), 413)
        problem(client.post("/v1/replays", content=b"{" + b" " * 2000 + b"}"), 413)


def test_trials_beyond_the_servers_maximum_is_422(client: TestClient) -> None:
    body = problem(client.post("/v1/plans?trials=100000", content=SEED_TEXT, headers=YAML), 422)
    assert body["parameter"] == "trials"
    problem(client.post("/v1/plans?trials=-1", content=SEED_TEXT, headers=YAML), 422)
    problem(client.post("/v1/replays", json={"plan_id": "0" * 32, "trials": 10**6}), 422)


def test_validating_with_no_trials_is_422(client: TestClient) -> None:
    # ?trials=0 (validate defaulting to true) was stored "validated": true with no trial run,
    # its Wilson interval 0–1 (the service hunt, F4); nothing is stored
    before = client.get("/v1/plans").json()
    body = problem(client.post("/v1/plans?trials=0", content=SEED_TEXT, headers=YAML), 422)
    assert body["parameter"] == "trials"
    assert "trials=0 leaves nothing to validate" in str(body["detail"])
    batch = {"tasks": [{"spec": SEED_TEXT, "trials": 0}]}
    (item,) = problem(client.post("/v1/plans/batch", json=batch), 422)["items"]
    assert (item["status"], item["problem"]["parameter"]) == (422, "tasks[0].trials")
    assert client.get("/v1/plans").json() == before


def test_time_budget_fails_the_job_with_504_and_the_worker_is_replaced(
    client: TestClient,
) -> None:
    with overridden(client.app, plan_timeout=0.002):  # type: ignore[arg-type]
        submitted = client.post("/v1/plans?trials=1", content=SEED_TEXT, headers=YAML)
    body = failed(client, submitted, 504)  # the job keeps the budget it was submitted with
    assert body["budget_seconds"] == pytest.approx(0.002)
    assert "time budget" in str(body["detail"])
    # The overrun worker was killed; its replacement runs the next job.
    replay = client.post("/v1/replays", json={"program": "BEGIN END", "spec": SEED_TEXT})
    assert done(client, replay)["nominal"]["outcome"] in {"success", "failure", "abort"}


# -- auth -----------------------------------------------------------------------------------------


def test_writes_need_the_token_reads_do_not(client: TestClient) -> None:
    with overridden(client.app, token="s3cret"):  # type: ignore[arg-type]
        for headers in ({}, {"Authorization": "Bearer wrong"}, {"Authorization": "Basic s3cret"}):
            answer = client.post("/v1/plans", content=SEED_TEXT, headers={**YAML, **headers})
            problem(answer, 401)
            assert answer.headers["www-authenticate"] == "Bearer"
        problem(client.post("/v1/replays", json={"plan_id": "0" * 32}), 401)
        problem(client.post("/v1/plans/batch", json={"tasks": [{"spec": SEED_TEXT}]}), 401)
        for url in (f"/v1/plans/{'0' * 32}", f"/v1/jobs/{'0' * 32}"):
            problem(client.delete(url), 401)
            wrong = client.delete(url, headers={"Authorization": "Bearer wrong"})
            problem(wrong, 401)
            right = client.delete(url, headers={"Authorization": "Bearer s3cret"})
            problem(right, 404)  # past the gate: nothing there
        authorised = {**YAML, "Authorization": "Bearer s3cret"}
        answer = client.post("/v1/plans", content=b"name: t\nframes: []\n", headers=authorised)
        assert answer.status_code == 422  # past the gate
        assert client.get("/v1/plans").status_code == 200
        assert client.get("/healthz").status_code == 200


def test_protected_reads_need_the_token(client: TestClient) -> None:
    with overridden(client.app, token="s3cret", protect_reads=True):  # type: ignore[arg-type]
        problem(client.get("/v1/plans"), 401)
        problem(client.get(f"/v1/plans/{'0' * 32}"), 401)
        problem(client.get(f"/v1/jobs/{'0' * 32}"), 401)
        ok = client.get("/v1/plans", headers={"Authorization": "Bearer s3cret"})
        assert ok.status_code == 200
        assert client.get("/healthz").status_code == 200


# -- unknown ids, routes, methods -----------------------------------------------------------------


@pytest.mark.parametrize(
    "path",
    [
        f"/v1/plans/{'0' * 32}",
        f"/v1/plans/{'0' * 32}/program.al",
        "/v1/plans/x'%20OR%201=1",
        f"/v1/jobs/{'0' * 32}",
        "/v1/jobs/x'%20OR%201=1",
        "/v2",
    ],
)
def test_unknown_ids_and_routes_are_404(client: TestClient, path: str) -> None:
    problem(client.get(path), 404)
    if path.startswith("/v1/") and not path.endswith(".al"):
        problem(client.delete(path), 404)


def test_unknown_plan_in_replay_is_404(client: TestClient) -> None:
    problem(client.post("/v1/replays", json={"plan_id": "f" * 32}), 404)


def test_wrong_method_is_405(client: TestClient) -> None:
    problem(client.delete("/v1/plans"), 405)


@pytest.mark.parametrize(
    ("body", "loc", "why"),
    [
        # ReplayIn (server/schemas.py): a program needs its spec, a spec excludes a plan_id,
        # the seed is ge=0, and unknown keys are refused.
        ({}, ["body"], "give 'program' and 'spec', or 'plan_id'"),
        ({"program": "BEGIN END"}, ["body"], "give 'program' and 'spec', or 'plan_id'"),
        (
            {"spec": {"name": "t"}, "plan_id": "0" * 32, "program": "x"},
            ["body"],
            "give either 'spec' or 'plan_id', not both",
        ),
        ({"plan_id": "0" * 32, "seed": -1}, ["body", "seed"], "greater than or equal to 0"),
        (
            {"plan_id": "0" * 32, "seed": 2**32},
            ["body", "seed"],
            "less than or equal to 4294967295",
        ),
        ({"plan_id": "0" * 32, "extra": 1}, ["body", "extra"], "Extra inputs are not permitted"),
    ],
    ids=[
        "empty",
        "program-alone",
        "spec-and-plan",
        "negative-seed",
        "seed-over-32-bits",
        "unknown-key",
    ],
)
def test_malformed_replay_requests_are_422(
    client: TestClient, body: dict[str, object], loc: list[str], why: str
) -> None:
    answer = problem(client.post("/v1/replays", json=body), 422)
    errors = answer["errors"]
    assert isinstance(errors, list) and len(errors) == 1, errors  # one fault per body
    assert errors[0]["loc"] == loc and why in errors[0]["msg"], errors


# -- listing --------------------------------------------------------------------------------------


def _store_plan(client: TestClient, name: str) -> str:
    store = client.app.state.service.store  # type: ignore[attr-defined]
    plan, created = store.add(
        NewPlan(
            content_hash=f"test-{name}",
            task_name=name,
            spec_text="name: x\n",
            spec_media_type="yaml",
            spec={"name": name},
            options={
                "trials": 0,
                "seed": 0,
                "try_harder": False,
                "exhaustive": False,
                "validate": False,
            },
            result={"strategy": {"name": f"s-{name}", "time": {"expected_time": 6.0}}},
            program="BEGIN END\n",
            validation=None,
        )
    )
    assert created
    return str(plan.id)


def test_listing_pages_newest_first(client: TestClient) -> None:
    ids = [_store_plan(client, f"list-{i}") for i in range(5)]
    seen: list[str] = []
    url: str | None = "/v1/plans?limit=2"
    while url is not None:
        page = client.get(url).json()
        assert len(page["items"]) <= 2
        seen += [item["id"] for item in page["items"]]
        url = page["next"]
    assert [i for i in seen if i in ids] == ids[::-1]
    first = client.get("/v1/plans?limit=1").json()["items"][0]
    assert first["strategy"] == "s-list-4" and first["expected_time"] == 6.0
    assert first["links"]["self"] == f"/v1/plans/{first['id']}"
    problem(client.get("/v1/plans?limit=0"), 422)
    problem(client.get("/v1/plans?cursor=abc"), 422)


def test_stored_plan_and_program_are_served(client: TestClient) -> None:
    plan_id = _store_plan(client, "served")
    body = client.get(f"/v1/plans/{plan_id}").json()
    assert body["id"] == plan_id and body["task"] == "served" and body["validation"] is None
    program = client.get(f"/v1/plans/{plan_id}/program.al")
    assert program.status_code == 200
    assert program.headers["content-type"].startswith("text/plain")
    assert program.text == "BEGIN END\n"


# -- a genuine bug is a generic 500, logged -------------------------------------------------------


def test_a_bug_is_a_generic_logged_500(
    client: TestClient, caplog: pytest.LogCaptureFixture
) -> None:
    app = client.app

    @app.get("/boom", include_in_schema=False)  # type: ignore[attr-defined, untyped-decorator]
    async def boom() -> None:
        raise RuntimeError("secret internal detail")

    unchecked = TestClient(app, raise_server_exceptions=False)  # type: ignore[arg-type]
    with caplog.at_level(logging.ERROR, logger="server"):
        answer = unchecked.get("/boom")
    body = problem(answer, 500)
    assert "secret" not in answer.text
    assert re.fullmatch(r"[0-9a-f]{12}", str(body["request_id"]))
    assert any(body["request_id"] in r.getMessage() and r.exc_info for r in caplog.records)


# -- the seed's round trip ------------------------------------------------------------------------


def test_seed_round_trip(client: TestClient) -> None:
    from synth.al.parser import parse_program

    answer = client.post("/v1/plans?trials=2", content=SEED_TEXT, headers=YAML)
    assert answer.status_code == 202, answer.text
    job = answer.json()
    assert answer.headers["location"] == f"/v1/jobs/{job['id']}"
    assert job["kind"] == "plan" and job["state"] in ("queued", "running")
    assert job["task"] == "seed_4_8" and job["result"] is None
    plan = done(client, answer)
    assert plan["task"] == "seed_4_8"
    assert plan["strategy"]["search"] is not None  # seed §4.8: search needed
    assert plan["strategy"]["tap"] is None  # ... and no tap
    assert plan["validation"] is not None
    assert client.get(plan["links"]["self"]).json() == plan
    program = client.get(plan["links"]["program"])
    assert program.status_code == 200 and program.headers["content-type"].startswith("text/plain")
    assert program.text == plan["program"]
    parse_program(program.text)
    # An identical submission is answered from the store: a job that is done at once.
    again = client.post("/v1/plans?trials=2", content=SEED_TEXT, headers=YAML)
    assert again.status_code == 201, again.text
    reused = again.json()
    assert reused["state"] == "done" and reused["reused"] is True
    assert reused["plan_id"] == plan["id"] and reused["result"] == plan
    assert reused["id"] != job["id"]


def test_no_feasible_strategy_fails_the_job_with_the_planners_reasons(client: TestClient) -> None:
    far = SEED_TEXT.replace("[24.1 cm, 117 cm, 0 cm]", "[24.1 cm, 517 cm, 0 cm]", 1)
    submitted = client.post("/v1/plans?validate=false", content=far, headers=YAML)
    body = failed(client, submitted, 422)
    assert body["title"] == "No feasible strategy" and body["task"] == "seed_4_8"
    reasons = body["reasons"]
    assert isinstance(reasons, list) and reasons
    assert all(set(r) == {"candidate", "reason"} for r in reasons)
    assert any("no arm solution" in r["reason"] for r in reasons)


def test_a_task_too_large_for_the_planner_fails_its_job_with_422_not_500(
    client: TestClient,
) -> None:
    tight = SEED_TEXT.replace("dr_ok: 0.762 cm", "dr_ok: 0.001 cm", 1)
    answer = client.post("/v1/plans?validate=false", content=tight, headers=YAML)
    failed(client, answer, 422)


def test_a_new_app_on_the_same_file_serves_the_plans_and_jobs(client: TestClient) -> None:
    # A real restart after kill -9 is in test_server_process.py; this is the in-process twin.
    submitted = client.post("/v1/plans?validate=false", content=SEED_TEXT, headers=YAML)
    plan = done(client, submitted)
    job = client.get(submitted.headers["location"]).json()
    url = client.app.state.service.store.url  # type: ignore[attr-defined]
    with client_for(Settings(db_url=url, workers=1)) as second:
        again = second.get(plan["links"]["self"])
        assert again.status_code == 200
        assert again.json() == plan
        assert second.get(submitted.headers["location"]).json() == job
        listed = second.get("/v1/plans?limit=100").json()["items"]
        assert plan["id"] in {item["id"] for item in listed}


# -- replays ----------------------------------------------------------------------------------


def test_plan_is_validated_by_replay_and_replays_are_reproducible(client: TestClient) -> None:
    plan = done(client, client.post("/v1/plans?trials=3&seed=5", content=SEED_TEXT, headers=YAML))
    validation = plan["validation"]
    assert set(validation) >= {"ok", "nominal", "monte_carlo"}
    assert validation["monte_carlo"]["trials"] == 3 and validation["monte_carlo"]["seed"] == 5
    submitted = client.post("/v1/replays", json={"plan_id": plan["id"], "trials": 3, "seed": 5})
    assert submitted.status_code == 202 and submitted.json()["kind"] == "replay"
    by_id = done(client, submitted)
    assert by_id["monte_carlo"] == validation["monte_carlo"]
    inline = done(
        client,
        client.post(
            "/v1/replays",
            json={"program": plan["program"], "spec": SEED_TEXT, "trials": 3, "seed": 5},
        ),
    )
    assert inline["nominal"] == by_id["nominal"]
    as_json = done(
        client,
        client.post(
            "/v1/replays",
            json={"program": plan["program"], "spec": yaml.safe_load(SEED_TEXT), "trials": 0},
        ),
    )
    assert as_json["nominal"] == validation["nominal"]


def test_replay_of_a_program_that_does_not_parse_fails_at_its_line(client: TestClient) -> None:
    program = "BEGIN\nMOVE BMANIP TO ;\nEND\n"
    submitted = client.post("/v1/replays", json={"program": program, "spec": SEED_TEXT})
    body = failed(client, submitted, 422)
    assert body["title"] == "AL syntax error"
    assert body["line"] == 2 and isinstance(body["column"], int)


def test_replay_of_a_spec_that_does_not_validate_is_422(client: TestClient) -> None:
    body = problem(
        client.post("/v1/replays", json={"program": "BEGIN END", "spec": {"name": "t"}}), 422
    )
    assert body["path"] == "frames"


def test_plan_document_is_synth_plan_json_plus_the_servers_keys(
    client: TestClient, capsys: pytest.CaptureFixture[str]
) -> None:
    from synth.cli import main

    # validate=false proves by the nominal replay alone, as --proof-trials 0 does.
    assert main(["plan", str(SEED_TASK), "--json", "--proof-trials", "0"]) == 0
    cli = json.loads(capsys.readouterr().out)
    served = done(client, client.post("/v1/plans?validate=false", content=SEED_TEXT, headers=YAML))
    assert served["proof"]["passed"] and served["proof"]["decided_by"] == "nominal-only"
    assert set(cli) <= set(served)
    assert set(served) - set(cli) <= {
        "id",
        "task",
        "created_at",
        "content_hash",
        "options",
        "validation",
        "links",
    }
    for key in set(cli) - {"planning_time", "counters"}:
        assert served[key] == cli[key], key
