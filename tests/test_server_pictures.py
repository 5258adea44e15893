"""The service draws a stored plan: ``plan.svg``, ``view.html`` and ``trace.json``.

Oracles: the stored plan's own JSON (its search record's numbers give the search points by the
seed's rule, L2743–2770; its validation's nominal run gives the trace's outcome and time) and
its program text (the view shows it).
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterator

import pytest
from _paths import SEED_TASK
from _server_support import YAML, client_for, done
from _svg import SvgFigure
from fastapi.testclient import TestClient

from server.settings import Settings


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    db = tmp_path_factory.mktemp("db") / "plans.db"
    with client_for(Settings(db_url=str(db), workers=1, plan_timeout=120.0)) as c:
        yield c


@pytest.fixture(scope="module")
def plan(client: TestClient) -> dict:
    answer = client.post("/v1/plans?trials=2", content=SEED_TASK.read_text(), headers=YAML)
    return done(client, answer)


def seed_rule_count(search: dict) -> int:
    """Points the program tries: the first attempt and the ring points inside the filter."""
    count = 1
    for k in range(1, search["rings"] + 1):
        radius, w = k * search["step"], 0.0
        while w < 2 * math.pi:
            x, y = radius * math.cos(w), radius * math.sin(w)
            count += abs(x) <= search["dx"] and abs(y) <= search["dy"]
            w += search["step"] / radius
    return count


def test_plan_svg_is_the_stored_plans_picture(client: TestClient, plan: dict) -> None:
    answer = client.get(f"/v1/plans/{plan['id']}/plan.svg")
    assert answer.status_code == 200, answer.text
    assert answer.headers["content-type"].startswith("image/svg+xml")
    svg = SvgFigure(answer.content)
    points = svg.uses("search-points")
    assert len(points) == seed_rule_count(plan["strategy"]["search"])
    assert svg.has("footprint-certified") and svg.has("height-dtry")


def test_view_html_shows_the_stored_program(client: TestClient, plan: dict) -> None:
    answer = client.get(f"/v1/plans/{plan['id']}/view.html")
    assert answer.status_code == 200, answer.text
    assert answer.headers["content-type"].startswith("text/html")
    assert "WebGLRenderer" in answer.text
    found = re.search(r'<script type="application/json" id="scene">(.*?)</script>', answer.text)
    assert found is not None
    scene = json.loads(found.group(1))
    assert scene["program"] == plan["program"].splitlines()
    assert scene["lines"][-1] > 1 and len(scene["times"]) == len(scene["lines"])


def test_trace_json_is_the_validated_nominal_run(client: TestClient, plan: dict) -> None:
    answer = client.get(f"/v1/plans/{plan['id']}/trace.json")
    assert answer.status_code == 200, answer.text
    trace = answer.json()
    nominal = plan["validation"]["nominal"]
    assert trace["schema"] == "synth.trace/1" and trace["trial"] is None
    assert trace["outcome"]["outcome"] == nominal["outcome"] == "success"
    assert trace["samples"][-1]["t"] == pytest.approx(nominal["time"], abs=1e-9)
    trial = client.get(f"/v1/plans/{plan['id']}/trace.json?trial=1&seed=5").json()
    assert trial["trial"] == 1 and trial["seed"] == 5


@pytest.mark.parametrize("what", ["plan.svg", "view.html", "trace.json"])
def test_unknown_plan_is_404(client: TestClient, what: str) -> None:
    answer = client.get(f"/v1/plans/{'0' * 32}/{what}")
    assert answer.status_code == 404
    assert answer.headers["content-type"].startswith("application/problem+json")


def test_negative_trial_is_422(client: TestClient, plan: dict) -> None:
    assert client.get(f"/v1/plans/{plan['id']}/trace.json?trial=-1").status_code == 422
