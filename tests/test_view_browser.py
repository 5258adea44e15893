"""``synth view``: the page renders in headless Chromium, the arm where the camera puts it.

The screenshot's pixels are checked against the scene's own camera (:func:`project`): the hand
at the frozen time ``?t=…`` (the trace's pose) projects onto arm-coloured pixels; two times give
different pictures; the DOM after the script ran highlights the trace's AL line at that time.
Chromium comes from Debian's package (``make test`` installs it when root); without it the
browser tests skip, saying why.
"""

from __future__ import annotations

import bisect
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from _paths import SEED_TASK
from _tasks import synthesized
from PIL import Image

from synth.cli import main
from synth.pictures.view import CANVAS, Camera, project, view_html, view_scene
from synth.replay.run import replay_context
from synth.replay.trace import Trace, record_run

WINDOW = (CANVAS[0] + 360, CANVAS[1])


def find_chromium() -> str | None:
    """The Chromium binary; installed from Debian's packages when root and missing."""
    found = shutil.which("chromium") or shutil.which("chromium-browser")
    if found or os.name != "posix" or os.geteuid() != 0 or not shutil.which("apt-get"):
        return found
    env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
    install = ["apt-get", "install", "-y", "--no-install-recommends", "chromium"]
    for commands in ([install], [["apt-get", "update"], install]):
        for command in commands:
            subprocess.run(command, env=env, capture_output=True, timeout=1200, check=False)
        if shutil.which("chromium"):
            return shutil.which("chromium")
    return None


@pytest.fixture(scope="module")
def chromium() -> str:
    binary = find_chromium()
    if binary is None:
        pytest.skip(
            "headless Chromium is not installed and cannot be installed here "
            "(needs root and apt-get: `apt-get install -y chromium`)"
        )
    return binary


@pytest.fixture(scope="module")
def page(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict, Trace]:
    program = synthesized(SEED_TASK).program
    context = replay_context(program, SEED_TASK)
    trace = record_run(context, program="seed.al")
    scene = view_scene(context, trace, program)
    path = tmp_path_factory.mktemp("view") / "view.html"
    path.write_text(view_html(scene), encoding="utf-8")
    return path, scene, trace


def browse(chromium: str, url: str, tmp: Path, *args: str) -> subprocess.CompletedProcess[str]:
    flags = [
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-background-networking",
        "--disable-component-update",
        "--no-first-run",
        f"--user-data-dir={tmp / 'profile'}",
        "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader",
        "--hide-scrollbars",
        f"--window-size={WINDOW[0]},{WINDOW[1]}",
    ]
    return subprocess.run(
        [chromium, *flags, *args, url], capture_output=True, text=True, timeout=120, check=False
    )


def screenshot(chromium: str, page: Path, t: float, tmp: Path) -> np.ndarray:
    out = tmp / f"shot_{t}.png"
    result = browse(chromium, f"{page.as_uri()}?t={t}", tmp, f"--screenshot={out}")
    assert out.exists(), result.stderr[-2000:]
    return np.asarray(Image.open(out).convert("RGB"), dtype=int)


def sample_at(trace: Trace, t: float) -> int:
    times = [s.t for s in trace.samples]
    return max(0, bisect.bisect_right(times, t) - 1)


def arm_pixels(image: np.ndarray, column: float, row: float, half: int = 14) -> int:
    """Pixels of the arm's blues (COLOURS arm / hand) in a window about (column, row)."""
    c, r = round(column), round(row)
    window = image[max(r - half, 0) : r + half, max(c - half, 0) : c + half]
    red, green, blue = window[..., 0], window[..., 1], window[..., 2]
    return int(np.count_nonzero((blue > red + 40) & (blue > green + 20)))


def test_the_arm_is_drawn_where_the_camera_puts_its_hand(chromium, page, tmp_path) -> None:
    path, scene, trace = page
    camera = Camera(
        **{k: tuple(v) if isinstance(v, list) else v for k, v in scene["camera"].items()}
    )
    shots = {}
    for t in (0.5, 3.5):
        image = screenshot(chromium, path, t, tmp_path)
        assert image.shape[:2] == (WINDOW[1], WINDOW[0])
        shots[t] = image[:, : CANVAS[0]]
        hand = trace.samples[sample_at(trace, t)].hand
        # a point 3 cm back along the hand's approach axis: inside the wrist, not between pads
        wrist = hand.act(np.array([0.0, 0.0, -0.03]))
        column, row = project(camera, wrist)
        assert 0 <= column < CANVAS[0] and 0 <= row < CANVAS[1]
        assert arm_pixels(shots[t], column, row) > 50, (t, column, row)
        background = np.array([0xF4, 0xF4, 0xF4])
        assert np.count_nonzero(np.all(shots[t] == background, axis=-1)) > 1000  # not all arm
    changed = np.any(np.abs(shots[0.5] - shots[3.5]) > 30, axis=-1)
    assert changed.mean() > 0.01
    # the hand moved on screen between the two times: its projections are apart
    a = project(camera, trace.samples[sample_at(trace, 0.5)].hand.translation)
    b = project(camera, trace.samples[sample_at(trace, 3.5)].hand.translation)
    assert np.hypot(a[0] - b[0], a[1] - b[1]) > 30


def test_the_page_highlights_the_line_being_executed(chromium, page, tmp_path) -> None:
    path, _, trace = page
    for t in (1.0, 3.5):
        result = browse(chromium, f"{path.as_uri()}?t={t}", tmp_path, "--dump-dom")
        body = re.search(r"<body([^>]*)>", result.stdout)
        assert body is not None, result.stderr[-2000:]
        line = trace.samples[sample_at(trace, t)].line
        assert f'data-line="{line}"' in body.group(1) and 'data-ready="1"' in body.group(1)
        rows = re.findall(r'<div data-line="(\d+)" class="current">', result.stdout)
        assert rows == [str(line)]


def test_the_page_is_self_contained(page) -> None:
    html = page[0].read_text(encoding="utf-8")
    assert not re.search(r"<(script|link|img)[^>]+(src|href)=", html)
    assert "WebGLRenderer" in html and "Three.js Authors" in html  # three.js inlined, licence


def test_cli_writes_the_view(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    al = tmp_path / "seed.al"
    al.write_text(synthesized(SEED_TASK).program, encoding="utf-8")
    out = tmp_path / "v" / "view.html"
    assert main(["view", str(SEED_TASK), str(al), "-o", str(out)]) == 0
    assert "synth view" in out.read_text(encoding="utf-8")
    assert f"view of {al} on seed_4_8 written to {out}" in capsys.readouterr().out
    assert main(["view", str(SEED_TASK), str(tmp_path / "missing.al"), "-o", str(out)]) == 2
    # without a program it plans one and writes it to no file: it said "view of seed_4_8.al"
    assert main(["view", str(SEED_TASK), "-o", str(out), "--proof-trials", "0"]) == 0
    said = capsys.readouterr().out
    assert "view of the program planned for it on seed_4_8 written to" in said


def test_the_view_to_dash_goes_to_standard_output(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # "-o -" wrote a file named "-" in the working directory, which a later "synth plan -"
    # run there could read as its task
    monkeypatch.chdir(tmp_path)
    al = tmp_path / "seed.al"
    al.write_text(synthesized(SEED_TASK).program, encoding="utf-8")
    assert main(["view", str(SEED_TASK), str(al), "-o", "-"]) == 0
    out, err = capsys.readouterr()
    assert out.startswith("<!DOCTYPE html>") and "synth view" in out
    assert "written to standard output (nominal run: success" in err
    assert not (tmp_path / "-").exists()


def test_a_view_named_other_than_html_is_refused_before_any_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # `-o v.png` wrote the HTML page into v.png (while `synth plan --svg x.png` does write a
    # PNG): the name is refused, exit 2, before the task is planned or replayed
    assert main(["view", str(SEED_TASK), "-o", str(tmp_path / "v.png")]) == 2
    assert "the view is an HTML page; name it .html" in capsys.readouterr().err
    assert not (tmp_path / "v.png").exists()


def test_a_program_that_never_moves_is_refused_with_why(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # No motion, no samples: it was exit 70, "ValueError: the trace has no samples".
    al = tmp_path / "abort.al"
    al.write_text('ABORT("NOT TODAY");\n', encoding="utf-8")
    out = tmp_path / "view.html"
    assert main(["view", str(SEED_TASK), str(al), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "the program ends (abort at line 1: NOT TODAY) before it makes a motion" in err
    assert not out.exists()


def test_text_from_the_task_cannot_break_out_of_the_scene_data() -> None:
    # A task named "<!--<script>" switched the HTML parser into a script's escaped state and
    # took the page's own script with it (the program panel stayed empty in Chromium).
    import html.parser
    import json

    hostile = "<!--<script></script>--> & </SCRIPT>"
    scene = {"title": hostile, "program": [hostile], "nested": {"n": [1, 2.5, None]}}
    page = view_html(scene)

    class Scripts(html.parser.HTMLParser):
        def __init__(self) -> None:
            super().__init__()
            self.data: list[str] = []
            self.inside = False

        def handle_starttag(self, tag: str, attrs: list) -> None:  # type: ignore[type-arg]
            self.inside = tag == "script" and ("id", "scene") in attrs

        def handle_endtag(self, tag: str) -> None:
            self.inside = False

        def handle_data(self, data: str) -> None:
            if self.inside:
                self.data.append(data)

    parser = Scripts()
    parser.feed(page)
    assert json.loads("".join(parser.data)) == scene  # the element holds the whole document
    payload = page.split('id="scene">', 1)[1].split("</script>", 1)[0]
    assert "<" not in payload and ">" not in payload and "&" not in payload
    assert "&lt;!--&lt;script&gt;" in page  # and the <title> is escaped as text
