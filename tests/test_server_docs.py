"""The interactive docs work offline: ``/docs`` and ``/redoc`` load only the vendored assets.

Oracle: the HTML's own references (every ``src``/``href``, and any URL in its inline script)
must be paths on this server, each of which answers 200 with the asset's content type and the
exact bytes of the file in ``server/static/``.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from html.parser import HTMLParser
from pathlib import Path

import pytest
from _paths import ROOT
from _server_support import client_for
from fastapi.testclient import TestClient

from server.settings import Settings

STATIC = ROOT / "server" / "static"
CONTENT_TYPES = {
    ".js": ("text/javascript", "application/javascript"),
    ".css": ("text/css",),
    ".png": ("image/png",),
}


class _References(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.urls: list[str] = []
        self.scripts: list[str] = []
        self._in_script = False

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.urls += [value for name, value in attrs if name in ("src", "href") and value]
        self.urls += [value for name, value in attrs if name == "spec-url" and value]
        self._in_script = tag == "script"

    def handle_endtag(self, tag: str) -> None:
        self._in_script = False

    def handle_data(self, data: str) -> None:
        if self._in_script:
            self.scripts.append(data)


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    db = tmp_path_factory.mktemp("docs") / "docs.db"
    with client_for(Settings(db_url=str(db), workers=1)) as c:
        yield c


@pytest.mark.parametrize(
    ("page", "assets"),
    [
        ("/docs", {"/static/swagger-ui/swagger-ui-bundle.js", "/static/swagger-ui/swagger-ui.css"}),
        ("/redoc", {"/static/redoc/redoc.standalone.js"}),
    ],
)
def test_docs_pages_reference_only_local_assets(
    client: TestClient, page: str, assets: set[str]
) -> None:
    answer = client.get(page)
    assert answer.status_code == 200 and answer.headers["content-type"].startswith("text/html")
    refs = _References()
    refs.feed(answer.text)
    assert assets <= set(refs.urls)
    inline = re.findall(r"""['"]((?:https?:)?//[^'"]+|/[^'"\s]*)['"]""", " ".join(refs.scripts))
    for url in refs.urls + inline:
        assert url.startswith("/") and not url.startswith("//"), f"{page} loads {url}"
    assert "cdn." not in answer.text and "fonts.googleapis" not in answer.text
    for url in refs.urls:
        if url.startswith("/static/"):
            served = client.get(url)
            assert served.status_code == 200, url
            kind = served.headers["content-type"].split(";")[0]
            assert kind in CONTENT_TYPES[Path(url).suffix], (url, kind)
            assert served.content == (STATIC / url.removeprefix("/static/")).read_bytes()
        else:
            assert client.get(url).status_code == 200, url  # the OpenAPI document


def test_vendored_assets_carry_their_licences() -> None:
    for directory, licence in (("swagger-ui", "Apache License"), ("redoc", "MIT License")):
        assert licence in (STATIC / directory / "LICENSE").read_text()
    readme = (STATIC / "README.md").read_text()
    assert "swagger-ui-dist" in readme and "5.35.0" in readme and "2.5.4" in readme


def test_an_unknown_asset_is_a_404_problem(client: TestClient) -> None:
    answer = client.get("/static/swagger-ui/nothing.js")
    assert answer.status_code == 404
    assert answer.headers["content-type"].startswith("application/problem+json")
    assert client.get("/static/../settings.py").status_code == 404
