"""No 500 on client input: the inputs that used to crash the service get a 4xx problem (as an
answer, or as the problem of the job they became), every status a route can answer is in the
OpenAPI schema, and an unexpected error is a 500 problem the app answers itself (it does not
propagate to the server, which would drop the connection)."""

from __future__ import annotations

import asyncio
import json
from collections.abc import Iterator
from pathlib import Path

import httpx2 as httpx
import pytest
from _paths import SEED_TASK
from _server_support import YAML, client_for, failed, overridden
from fastapi.testclient import TestClient

from server.main import create_app
from server.settings import Settings

NO_JOINTS_URDF = "<?xml version='1.0'?>\n<robot name='plank'><link name='base'/></robot>\n"


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    db = tmp_path_factory.mktemp("robust") / "plans.db"
    with client_for(Settings(db_url=str(db), workers=1, plan_timeout=60.0)) as c:
        yield c


def problem(response: httpx.Response, status: int) -> dict[str, object]:
    assert response.status_code == status, response.text
    assert response.headers["content-type"].startswith("application/problem+json")
    body = response.json()
    assert body["status"] == status and body["title"] and body["detail"]
    return dict(body)


def test_a_cursor_beyond_64_bits_is_422_not_a_database_overflow(client: TestClient) -> None:
    body = problem(client.get("/v1/plans", params={"cursor": str(2**63)}), 422)
    assert "cursor" in str(body["detail"])
    assert client.get("/v1/plans", params={"cursor": str(2**63 - 1)}).status_code == 200


def test_a_number_of_thousands_of_digits_is_422_at_its_line_not_a_500(client: TestClient) -> None:
    # Python's int() refuses over 4 300 digits with a ValueError of its own: it was a 500 on
    # every route that reads a task (plans, batch, replays), with a traceback in the log.
    huge = "9" * 5000
    spec = SEED_TASK.read_text(encoding="utf-8").replace("name: seed_4_8", f"name: {huge}", 1)
    body = problem(client.post("/v1/plans", content=spec.encode(), headers=YAML), 422)
    assert "a number written with 5000 characters (more than 100)" in str(body["detail"])
    assert body["path"] == "name"
    replay = client.post("/v1/replays", json={"program": "BEGIN END", "spec": spec, "trials": 1})
    problem(replay, 422)


def test_a_json_body_that_is_not_utf8_is_a_documented_400(client: TestClient) -> None:
    answer = client.post(
        "/v1/replays", content=b'{"program": "\xff"}', headers={"Content-Type": "application/json"}
    )
    problem(answer, 400)
    schema = client.get("/openapi.json").json()
    assert "400" in schema["paths"]["/v1/replays"]["post"]["responses"]


def test_every_route_documents_the_statuses_the_service_answers(client: TestClient) -> None:
    schema = client.get("/openapi.json").json()
    # Submissions: the job's outcome (504 over the budget, 422 no strategy, …) is the job's
    # problem, not the POST's answer.
    for path in ("/v1/plans", "/v1/replays", "/v1/plans/batch"):
        responses = schema["paths"][path]["post"]["responses"]
        assert "202" in responses and ("201" in responses) == (path != "/v1/plans/batch"), path
        for status in ("400", "401", "408", "413", "422", "429", "500", "503"):
            assert status in responses, (path, status)
            assert "application/problem+json" in responses[status]["content"]
    jobs = schema["paths"]["/v1/jobs/{job_id}"]
    assert {"401", "404", "422"} <= set(jobs["get"]["responses"])
    wait = next(p for p in jobs["get"]["parameters"] if p["name"] == "wait")
    assert wait["schema"]["minimum"] == 0
    for path in ("/v1/jobs/{job_id}", "/v1/plans/{plan_id}"):
        responses = schema["paths"][path]["delete"]["responses"]
        assert {"204", "401", "404"} <= set(responses), path
        assert "application/problem+json" in responses["404"]["content"]
    listing = schema["paths"]["/v1/plans"]["get"]
    cursor = next(p for p in listing["parameters"] if p["name"] == "cursor")
    assert cursor["schema"]["anyOf"][0]["maximum"] == 2**63 - 1


def test_an_in_directory_urdf_without_joints_fails_its_job_with_422(
    client: TestClient, tmp_path: Path
) -> None:
    models = tmp_path / "models"
    models.mkdir()
    (models / "plank.urdf").write_text(NO_JOINTS_URDF)
    spec = SEED_TASK.read_text().replace(
        "    model: stanford", f"    urdf: {json.dumps('plank.urdf')}\n    tool_frame: base", 1
    )
    with overridden(client.app, model_dirs=(models,)):  # type: ignore[arg-type]
        answer = client.post("/v1/plans?validate=false", content=spec, headers=YAML)
    # The job runs with the model directories it was submitted under (the override has ended).
    body = failed(client, answer, 422)
    assert "no movable joints" in str(body["detail"])


def test_an_unhandled_error_is_answered_by_the_app_not_raised_to_the_server(
    tmp_path: Path,
) -> None:
    app = create_app(Settings(db_url=str(tmp_path / "boom.db"), workers=1))

    @app.get("/boom", include_in_schema=False)  # type: ignore[untyped-decorator]
    async def boom() -> None:
        raise KeyError("internal detail")

    async def scenario() -> httpx.Response:
        # raise_app_exceptions: an exception leaving the app would fail this call, as it makes
        # uvicorn close the connection after the 500.
        transport = httpx.ASGITransport(app=app, raise_app_exceptions=True)
        async with httpx.AsyncClient(transport=transport, base_url="http://t") as http:
            return await http.get("/boom")

    answer = asyncio.run(scenario())
    body = problem(answer, 500)
    assert body["type"] == "urn:synth:problem:internal"
    assert "internal detail" not in answer.text


def test_a_replay_of_an_error_block_too_thin_to_sample_fails_its_job_with_422(
    client: TestClient,
) -> None:
    # box.x − box.y within 1e-11 m: the loader's LP finds it feasible, the replay's rejection
    # sampler cannot hit so thin a band in a rectangle (synth.errors.parameters.SAMPLE_BUDGET);
    # it used to draw for ever, holding the worker until the time budget killed it. (An exact
    # equality, min == max, is refused by the loader.)
    spec = SEED_TASK.read_text(encoding="utf-8").replace(
        "      rz: 5 deg\n",
        "      rz: 5 deg\n      constraints:\n"
        "        - {terms: {x: 1, y: -1}, min: 0 cm, max: 1e-9 cm}\n",
        1,
    )
    answer = client.post("/v1/replays", json={"program": "BEGIN END", "spec": spec, "trials": 1})
    body = failed(client, answer, 422)
    assert body["title"] == "Invalid task specification"
    assert body["path"] == "uncertainty of box"
    assert str(body["detail"]).startswith("uncertainty of box: 0 of 100032 draws")
