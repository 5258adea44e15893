"""Nothing a client sends can cause a 500: hypothesis throws bytes, JSON, YAML, mutated seed
specs, replay requests, ids and query strings at every endpoint and checks the status is < 500.

The TestClient re-raises server exceptions, so a bug shows up here with its traceback.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Any
from urllib.parse import quote

import pytest
import yaml
from _paths import SEED_TASK
from _server_support import client_for
from fastapi.testclient import TestClient
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from server.settings import Settings

SEED_DATA: dict[str, Any] = yaml.safe_load(SEED_TASK.read_text())
FUZZ = settings(
    max_examples=30,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
CONTENT_TYPES = st.sampled_from(
    [
        "application/yaml",
        "application/json",
        "text/plain; charset=utf-8",
        "application/x-www-form-urlencoded",
        "application/vnd.api+json",
        "",
        "image/png",
        ";;;",
    ]
)
scalars = (
    st.none()
    | st.booleans()
    | st.integers(-(2**70), 2**70)
    | st.floats(allow_nan=False, allow_infinity=False)
    | st.text(max_size=20)
    | st.sampled_from(["1 cm", "5 deg", "-3 in", "1e308 m", "nan cm", "0 kg", "inf deg", "world"])
)
json_values = st.recursive(
    scalars,
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4)
    ),
    max_leaves=20,
)


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    db = tmp_path_factory.mktemp("fuzz") / "fuzz.db"
    fuzz_settings = Settings(db_url=str(db), workers=1, plan_timeout=5.0, max_body_bytes=64_000)
    with client_for(fuzz_settings) as c:
        yield c


def _no_500(response: Any) -> None:
    assert response.status_code < 500 or response.status_code in (503, 504), response.text
    if response.status_code >= 400:
        assert response.headers["content-type"].startswith("application/problem+json")


def _mutate(data: Any, path: list[int], value: Any) -> Any:
    """``data`` with the node reached by ``path`` (child indices, modulo) replaced by ``value``."""
    if not path or not isinstance(data, dict | list) or not data:
        return value
    if isinstance(data, dict):
        keys = list(data)
        key = keys[path[0] % len(keys)]
        return {**data, key: _mutate(data[key], path[1:], value)}
    i = path[0] % len(data)
    return [*data[:i], _mutate(data[i], path[1:], value), *data[i + 1 :]]


@FUZZ
@given(body=st.binary(max_size=2000), content_type=CONTENT_TYPES)
def test_plans_take_any_bytes(client: TestClient, body: bytes, content_type: str) -> None:
    _no_500(client.post("/v1/plans", content=body, headers={"Content-Type": content_type}))


@FUZZ
@given(data=json_values, as_yaml=st.booleans())
def test_plans_take_any_document(client: TestClient, data: Any, as_yaml: bool) -> None:
    if as_yaml:
        body, kind = yaml.safe_dump(data).encode(), "application/yaml"
    else:
        body, kind = json.dumps(data).encode(), "application/json"
    _no_500(client.post("/v1/plans", content=body, headers={"Content-Type": kind}))


@FUZZ
@given(path=st.lists(st.integers(0, 50), min_size=1, max_size=6), value=json_values)
def test_plans_take_any_mutation_of_the_seed(
    client: TestClient, path: list[int], value: Any
) -> None:
    spec = _mutate(SEED_DATA, path, value)
    _no_500(client.post("/v1/plans?validate=false&trials=0", json=spec))


@FUZZ
@given(
    request=st.fixed_dictionaries(
        {},
        optional={
            "program": st.text(max_size=200) | json_values,
            "spec": json_values | st.text(max_size=200),
            "plan_id": st.text(max_size=40) | json_values,
            "trials": json_values,
            "seed": json_values,
        },
    )
)
def test_replays_take_any_request(client: TestClient, request: dict[str, Any]) -> None:
    _no_500(client.post("/v1/replays", json=request))


@FUZZ
@given(
    plan_id=st.text(max_size=60).filter(lambda s: s not in ("", ".", "..")),
    query=st.dictionaries(
        st.sampled_from(["limit", "cursor", "trials", "seed", "validate", "x"]),
        st.text(max_size=12),
        max_size=3,
    ),
)
def test_reads_take_any_id_and_query(
    client: TestClient, plan_id: str, query: dict[str, str]
) -> None:
    params = "&".join(f"{quote(k)}={quote(v)}" for k, v in query.items())
    _no_500(client.get(f"/v1/plans?{params}"))
    _no_500(client.get(f"/v1/plans/{quote(plan_id, safe='')}"))
    _no_500(client.get(f"/v1/plans/{quote(plan_id, safe='')}/program.al"))


@FUZZ
@given(
    job_id=st.text(max_size=40).filter(lambda s: s not in ("", ".", "..")) | st.just("0" * 32),
    wait=st.text(max_size=8) | st.sampled_from(["0", "0.01", "-1", "1e9", "nan", "inf"]),
)
def test_jobs_take_any_id_and_wait(client: TestClient, job_id: str, wait: str) -> None:
    path = quote(job_id, safe="")
    _no_500(client.get(f"/v1/jobs/{path}?wait={quote(wait)}"))
    _no_500(client.delete(f"/v1/jobs/{path}"))
    _no_500(client.delete(f"/v1/plans/{path}"))


batch_tasks = st.fixed_dictionaries(
    {"spec": json_values | st.text(max_size=100) | st.just(SEED_DATA)},
    optional={
        "trials": json_values,
        "seed": json_values,
        "validate": json_values,
        "try_harder": json_values,
        "extra": json_values,
    },
)


@FUZZ
@given(
    batch=st.fixed_dictionaries(
        {},
        optional={
            "tasks": st.lists(batch_tasks | json_values, max_size=4) | json_values,
            "other": json_values,
        },
    )
)
def test_batches_take_any_request(client: TestClient, batch: dict[str, Any]) -> None:
    answer = client.post("/v1/plans/batch", json=batch)
    _no_500(answer)
    if answer.status_code == 202:  # every item is answered, each by itself
        document = answer.json()
        assert len(document["items"]) == len(batch["tasks"])
        for item in document["items"]:
            assert (item["job"] is None) == (item["problem"] is not None)
            if item["problem"] is not None:
                assert 400 <= item["problem"]["status"] < 500 or item["status"] == 503
