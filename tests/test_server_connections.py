"""Connection timeouts of ``synth serve`` (server/connections.py), over raw sockets against the
real app under uvicorn with the serve configuration: silent, slow-header, idle and slow-body
clients are dropped within their documented timeouts; a 500 keeps the connection open."""

from __future__ import annotations

import json
import socket
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import uvicorn

from server.connections import uvicorn_config
from server.main import create_app
from server.settings import Settings

HEADER_TIMEOUT = 1.0  # [s]
KEEP_ALIVE = 1.0  # [s]
BODY_TIMEOUT = 1.0  # [s]
SLACK = 1.5  # [s] scheduling slack on a loaded machine


@pytest.fixture(scope="module")
def address(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, int]]:
    settings = Settings(
        db_url=str(tmp_path_factory.mktemp("conn") / "plans.db"),
        workers=1,
        header_timeout=HEADER_TIMEOUT,
        keep_alive_timeout=KEEP_ALIVE,
        body_timeout=BODY_TIMEOUT,
    )
    app = create_app(settings)

    @app.get("/boom", include_in_schema=False)  # type: ignore[untyped-decorator]
    async def boom() -> None:
        raise RuntimeError("a bug")

    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    server = uvicorn.Server(uvicorn_config(app, settings, "127.0.0.1", 0, log_level="warning"))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [listener]}, daemon=True)
    thread.start()
    deadline = time.monotonic() + 60
    while not server.started and time.monotonic() < deadline:
        time.sleep(0.05)
    assert server.started
    try:
        yield listener.getsockname()
    finally:
        server.should_exit = True
        thread.join(timeout=30)


def closed_after(sock: socket.socket, limit: float) -> float:
    """Seconds until the server closes ``sock`` (reading and discarding), at most ``limit``."""
    started = time.monotonic()
    sock.settimeout(0.1)
    while time.monotonic() - started < limit:
        try:
            if sock.recv(65536) == b"":
                return time.monotonic() - started
        except TimeoutError:
            continue
        except ConnectionResetError:
            return time.monotonic() - started
    raise AssertionError(f"connection still open after {limit} s")


def read_response(sock: socket.socket) -> tuple[int, dict[str, str], bytes]:
    """One HTTP/1.1 response with a Content-Length from ``sock``."""
    sock.settimeout(30)
    data = b""
    while b"\r\n\r\n" not in data:
        chunk = sock.recv(65536)
        assert chunk, "connection closed before a response"
        data += chunk
    head, _, body = data.partition(b"\r\n\r\n")
    lines = head.decode("latin-1").split("\r\n")
    headers = {k.strip().lower(): v.strip() for k, v in (x.split(":", 1) for x in lines[1:])}
    length = int(headers["content-length"])
    while len(body) < length:
        body += sock.recv(65536)
    return int(lines[0].split()[1]), headers, body


def request(path: str) -> bytes:
    return f"GET {path} HTTP/1.1\r\nHost: t\r\n\r\n".encode()


def test_a_silent_connection_is_dropped_after_the_header_timeout(address: tuple[str, int]) -> None:
    with socket.create_connection(address) as sock:
        assert closed_after(sock, HEADER_TIMEOUT + SLACK) >= HEADER_TIMEOUT - 0.2


def test_a_slowloris_client_is_dropped_after_the_header_timeout(address: tuple[str, int]) -> None:
    with socket.create_connection(address) as sock:
        sock.sendall(b"GET /healthz HTTP/1.1\r\nHost: t\r\n")  # then headers, slowly
        started = time.monotonic()
        dropped = False
        for byte in b"X-Slow: 1\r\nX-Slow: 2\r\nX-Slow: 3\r\n" * 4:
            try:
                sock.sendall(bytes([byte]))
            except (BrokenPipeError, ConnectionResetError):
                dropped = True
                break
            time.sleep(0.05)
            if time.monotonic() - started > HEADER_TIMEOUT + SLACK:
                break
        if not dropped:
            closed_after(sock, 0.5)
        assert time.monotonic() - started < HEADER_TIMEOUT + SLACK + 0.5


def test_a_slow_header_after_a_response_is_dropped_too(address: tuple[str, int]) -> None:
    with socket.create_connection(address) as sock:
        sock.sendall(request("/healthz"))
        assert read_response(sock)[0] == 200
        started = time.monotonic()
        for byte in request("/healthz")[:-2]:  # each byte cancels uvicorn's keep-alive timer
            try:
                sock.sendall(bytes([byte]))
            except (BrokenPipeError, ConnectionResetError):
                break
            time.sleep(0.1)
        else:
            closed_after(sock, SLACK)
        assert time.monotonic() - started < HEADER_TIMEOUT + SLACK + 0.5


def test_an_idle_keep_alive_connection_is_closed(address: tuple[str, int]) -> None:
    with socket.create_connection(address) as sock:
        sock.sendall(request("/healthz"))
        assert read_response(sock)[0] == 200
        assert closed_after(sock, KEEP_ALIVE + SLACK) >= KEEP_ALIVE - 0.2


def test_a_slow_body_is_answered_408_and_closed(address: tuple[str, int]) -> None:
    with socket.create_connection(address) as sock:
        sock.sendall(
            b"POST /v1/plans HTTP/1.1\r\nHost: t\r\nContent-Type: application/yaml\r\n"
            b"Content-Length: 100\r\n\r\nname: t\n"
        )
        started = time.monotonic()
        status, headers, body = read_response(sock)
        assert status == 408 and headers["content-type"] == "application/problem+json"
        assert json.loads(body)["status"] == 408
        assert BODY_TIMEOUT - 0.2 <= time.monotonic() - started < BODY_TIMEOUT + SLACK
        closed_after(sock, SLACK)


def test_a_500_keeps_the_connection_alive(address: tuple[str, int]) -> None:
    with socket.create_connection(address) as sock:
        sock.sendall(request("/boom"))
        status, headers, body = read_response(sock)
        assert status == 500 and headers["content-type"] == "application/problem+json"
        assert json.loads(body)["type"] == "urn:synth:problem:internal"
        sock.sendall(request("/healthz"))  # the same connection serves the next request
        assert read_response(sock)[0] == 200


def test_the_serve_configuration_carries_the_settings(tmp_path: Path) -> None:
    settings = Settings(db_url=str(tmp_path / "x.db"), header_timeout=7, keep_alive_timeout=3)
    config = uvicorn_config(object(), settings, "127.0.0.1", 0)
    assert config.timeout_keep_alive == 3 and config.limit_concurrency == 256
    assert isinstance(config.http, type) and config.http.header_timeout == 7  # type: ignore[attr-defined]
