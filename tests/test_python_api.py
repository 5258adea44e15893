"""The Python API: ``import synth`` names the pipeline lazily, and the example of
``docs/python-api.md`` runs as a plain script (no ``__main__`` guard, two workers)."""

from __future__ import annotations

import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from _paths import ROOT

import synth
from synth.replay import trials

DOC = ROOT / "docs" / "python-api.md"


def _example() -> str:
    blocks = re.findall(r"```python\n(.*?)```", DOC.read_text(encoding="utf-8"), re.DOTALL)
    assert len(blocks) == 1
    return blocks[0]


def test_import_synth_is_lazy_and_names_the_pipeline() -> None:
    code = "import sys, synth; print(sorted(m for m in sys.modules if m.startswith('synth')))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "['synth']"
    for name in synth.__all__:
        value = getattr(synth, name)
        assert value.__doc__, name
    assert synth.synthesize is __import__("synth.pipeline").pipeline.synthesize
    with pytest.raises(AttributeError):
        _ = synth.no_such_name


def test_the_documented_example_runs_as_an_unguarded_script(tmp_path: Path) -> None:
    source = _example()
    assert "__main__" not in source and "workers=2" in source
    script = tmp_path / "example.py"
    script.write_text(source, encoding="utf-8")
    done = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, cwd=tmp_path, timeout=600
    )
    assert done.returncode == 0, done.stderr
    out = done.stdout
    assert "BrokenProcessPool" not in done.stderr
    assert re.search(r"^proof: proven: \d+ of \d+ replayed", out, re.MULTILINE), out
    assert "nominal: success" in out
    m = re.search(r"trials: \{(.*)\}", out)
    assert m and sum(int(n) for n in re.findall(r": (\d+)", m.group(1))) == 8
    assert re.search(r"trajectory: \d+ points, [1-9]\d* on guarded moves", out)


def _frame_check(tmp_path: Path, body: str) -> str:
    script = tmp_path / "probe.py"
    script.write_text(textwrap.dedent(body), encoding="utf-8")
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, check=True)
    return done.stdout.strip()


def test_start_method_spawns_unless_the_script_is_unguarded(tmp_path: Path) -> None:
    unguarded = "from synth.replay.trials import start_method\nprint(start_method())\n"
    guarded = (
        "from synth.replay.trials import start_method\n"
        "if __name__ == '__main__':\n    print(start_method())\n"
    )
    in_function = (
        "from synth.replay.trials import start_method\n"
        "def main():\n    print(start_method())\nmain()\n"
    )
    expected = "fork" if sys.platform.startswith("linux") else "None"
    assert _frame_check(tmp_path, unguarded) == expected
    assert _frame_check(tmp_path, guarded) == "spawn"
    # called from a function the unguarded top level calls: spawn would still re-run it
    assert _frame_check(tmp_path, in_function) == expected
    # pytest's own main is guarded
    assert trials.start_method() == "spawn"
