"""CLI habits: ``--version``, exit codes in ``--help``, ``-o -``, ``replay -``, rate and ETA,
and the plain default text of ``synth plan`` (records behind ``--records``, seed line
references behind ``--verbose``)."""

from __future__ import annotations

import io
import json
import re
import subprocess
import sys
from importlib.metadata import version
from pathlib import Path

import pytest
from _paths import SEED_PROGRAM, SEED_TASK

from synth.al.parser import parse_program
from synth.cli import (
    EXIT_BROKEN_PIPE,
    EXIT_INTERNAL,
    EXIT_INTERRUPTED,
    EXIT_REPLAY_FAILED,
    EXIT_USAGE,
    main,
)
from synth.progress import ProgressBar
from synth.report import strip_seed_references

SYNTH = [sys.executable, "-m", "synth.cli"]
SEED_REF = re.compile(r"seed L\d|\bL\d{4}\b|seed Eqn")


def test_version_comes_from_the_package_metadata(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out.strip() == f"synth {version('synth')}"


def test_help_lists_the_exit_codes(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["--help"])
    text = capsys.readouterr().out
    block = text[text.index("exit codes:") :]
    for code in (
        0,
        EXIT_REPLAY_FAILED,
        EXIT_USAGE,
        EXIT_INTERNAL,
        EXIT_INTERRUPTED,
        EXIT_BROKEN_PIPE,
    ):
        assert re.search(rf"^\s+{code}\s+\S", block, re.MULTILINE), code


def _to_stdout(argv: list[str], where: Path) -> subprocess.CompletedProcess[str]:
    """``synth argv`` run in ``where``, exit 0, and no file named ``-`` written there."""
    done = subprocess.run([*SYNTH, *argv], capture_output=True, text=True, cwd=where, check=False)
    assert done.returncode == 0, done.stderr
    assert not (where / "-").exists()
    return done


def test_plan_to_stdout_writes_only_the_program(tmp_path: Path) -> None:
    done = _to_stdout(["plan", str(SEED_TASK), "--proof-trials", "0", "-o", "-"], tmp_path)
    parse_program(done.stdout)
    assert done.stdout == SEED_PROGRAM.read_text(encoding="utf-8")
    assert "Decisions:" in done.stderr and "Decisions:" not in done.stdout


def test_replay_reads_the_program_from_stdin(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(sys, "stdin", io.StringIO(SEED_PROGRAM.read_text(encoding="utf-8")))
    assert main(["replay", "-", "--task", str(SEED_TASK), "--trials", "0"]) == 0
    from_stdin = capsys.readouterr().out
    # The same report as the file's, but for the program's name.
    assert main(["replay", str(SEED_PROGRAM), "--task", str(SEED_TASK), "--trials", "0"]) == 0
    from_file = capsys.readouterr().out
    assert from_stdin.splitlines()[0] == "replay <stdin> on task seed_4_8"
    assert from_stdin == from_file.replace(str(SEED_PROGRAM), "<stdin>", 1)
    assert "nominal: success: PIN1 seated in BH1" in from_stdin


def test_replay_from_stdin_names_stdin_in_errors(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(sys, "stdin", io.StringIO("MOVE BMANIP TO ;\n"))
    assert main(["replay", "-", "--task", str(SEED_TASK), "--trials", "0"]) == EXIT_USAGE
    assert "<stdin>" in capsys.readouterr().err


def test_progress_shows_rate_and_eta() -> None:
    now = [100.0]
    stream = io.StringIO()
    bar = ProgressBar(stream, width=60, label="proof", clock=lambda: now[0])
    assert "?trial/s" in bar.line(0, 100)  # no rate before the first trial
    now[0] += 20.0
    bar(40, 100)  # 40 in 20 s: 2 trials/s; 60 left: 30 s
    assert stream.getvalue().startswith("\rproof:  40%|")
    assert stream.getvalue().endswith("| 40/100 [00:20<00:30,  2.00trial/s]")
    now[0] += 10.0
    bar(50, 100)  # 50 in 30 s: 1.67 trials/s; 50 left: 30 s
    assert stream.getvalue().rstrip().endswith("| 50/100 [00:30<00:30,  1.67trial/s]")
    bar.close()
    assert stream.getvalue().endswith("\n")


def test_plan_text_leads_with_decisions_and_hides_records_and_seed_lines(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["plan", str(SEED_TASK), "--proof-trials", "0"]) == 0
    plain = capsys.readouterr().out
    head = plain.splitlines()
    assert head[0].startswith("Plan: ") and head[2] == "Decisions:"
    assert plain.index("Expected time") < plain.index("Proof:") < plain.index("Candidates")
    assert "PHL SPEC" not in plain and "NULL_RECORD" not in plain and "NILTRANS" not in plain
    assert not SEED_REF.search(plain)
    assert plain.count("grasp orientation") == 1 and plain.count("the hole's axis as it") == 1

    assert main(["plan", str(SEED_TASK), "--proof-trials", "0", "--records", "--verbose"]) == 0
    full = capsys.readouterr().out
    assert "PHL SPEC" in full and "GRASP DETERM: NILTRANS" in full
    assert "seed L2122" in full  # the pruning rule's reference, kept under --verbose


def test_seed_references_are_stripped_with_their_separators() -> None:
    assert strip_seed_references("kept (seed L2122; --try-harder keeps all)") == (
        "kept (--try-harder keeps all)"
    )
    assert strip_seed_references("Δr_ok (measured, seed L1963) exceeds") == (
        "Δr_ok (measured) exceeds"
    )
    assert strip_seed_references("First order (seed Eqn 3.5.1): Δx") == "First order: Δx"
    # refine.py's tilt refusal: it printed "(: grounds for rejection)"
    assert strip_seed_references("0.360° (seed §4.5.1: grounds for rejection)") == (
        "0.360° (grounds for rejection)"
    )
    assert strip_seed_references("no reference here (3 rings)") == "no reference here (3 rings)"


def test_serve_refuses_a_port_it_cannot_use(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # --port 99999 was an OverflowError from bind() with two tracebacks (exit 70)
    for port in ("99999", "-1", "http"):
        with pytest.raises(SystemExit) as refused:
            main(["serve", "--port", port])
        assert refused.value.code == EXIT_USAGE
        assert "argument --port:" in capsys.readouterr().err
    # a port in use was uvicorn's own exit 3, a code the help does not list
    import socket

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        done = subprocess.run(
            [*SYNTH, "serve", "--port", str(port), "--db", str(tmp_path / "p.db")],
            capture_output=True,
            text=True,
            timeout=120,
            check=False,
        )
    assert done.returncode == EXIT_USAGE, done.stderr[-2000:]
    assert f"synth serve: error: cannot listen on 127.0.0.1:{port}" in done.stderr
    assert "Traceback" not in done.stderr


@pytest.mark.parametrize("seed", ["-1", "4294967296"])
def test_a_seed_outside_32_bits_is_a_usage_error(
    capsys: pytest.CaptureFixture[str], seed: str
) -> None:
    # The CLI takes the service's range, 0 to 2³² − 1 (synth.seeds.MAX_SEED; the service
    # answers 422 outside it): a seed one surface takes and the other refuses would make a run
    # that cannot be repeated through the other.
    for command in (
        ["plan", str(SEED_TASK)],
        ["replay", str(SEED_PROGRAM), "--task", str(SEED_TASK)],
    ):
        with pytest.raises(SystemExit) as refused:
            main([*command, "--seed", seed])
        assert refused.value.code == EXIT_USAGE
        assert f"argument --seed: a seed is 0 to 4294967295, got {seed}" in (
            capsys.readouterr().err
        )


@pytest.mark.parametrize("option", ["--trace", "--svg", "--export-trajectory"])
def test_replay_outputs_are_checked_before_the_replay(
    option: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # A Monte Carlo study of minutes must not end in "cannot write": the path is refused before
    # the program is even read, naming its option, and nothing is made
    import synth.cli.replay

    def no_work(_path: str) -> str:
        raise AssertionError("read the program before checking the output path")

    monkeypatch.setattr(synth.cli.replay, "read_program", no_work)
    blocker = tmp_path / "file"
    blocker.write_text("x", encoding="utf-8")
    suffix = {"--trace": "t.json", "--svg": "p.svg", "--export-trajectory": "t.csv"}[option]
    target = blocker / suffix
    argv = ["replay", str(SEED_PROGRAM), "--task", str(SEED_TASK), "--trials", "5"]
    assert main([*argv, option, str(target)]) == EXIT_USAGE
    assert capsys.readouterr().err == (
        f"synth replay: error: {option} {target}: {blocker} is not a directory\n"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


def test_an_output_that_is_an_input_is_refused_and_the_input_kept(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # `synth plan task.yaml -o task.yaml` replaced the task with the program, exit 0 (the
    # fourth hunt); the same file under another name is the same file
    task = tmp_path / "task.yaml"
    program = tmp_path / "prog.al"
    task.write_bytes(SEED_TASK.read_bytes())
    program.write_bytes(SEED_PROGRAM.read_bytes())
    other_name = tmp_path / "sub" / ".." / "task.yaml"
    (tmp_path / "sub").mkdir()
    for argv, option, path, kind in [
        (["plan", str(task), "-o"], "--output", other_name, "the task file"),
        (
            ["replay", str(program), "--task", str(task), "--trace"],
            "--trace",
            program,
            "the program file",
        ),
        (
            ["replay", str(program), "--task", str(task), "--export-trajectory"],
            "--export-trajectory",
            task,
            "the task file",
        ),
        (["view", str(task), str(program), "-o"], "--output", program, "the program file"),
    ]:
        assert main([*argv, str(path)]) == EXIT_USAGE
        assert capsys.readouterr().err.endswith(
            f"error: {option} {path}: is {kind}; writing it would destroy it\n"
        )
    assert task.read_bytes() == SEED_TASK.read_bytes()
    assert program.read_bytes() == SEED_PROGRAM.read_bytes()


@pytest.mark.parametrize("one", [False, True], ids=["monte-carlo", "trial"])
def test_replay_trace_to_stdout_writes_only_the_trace(one: bool, tmp_path: Path) -> None:
    # `--trace -` wrote the trace and then the report to standard output: not JSON (the fourth
    # hunt). The report goes to standard error, as plan -o - does.
    runs = ["--trial", "2"] if one else ["--trials", "3"]
    argv = ["replay", str(SEED_PROGRAM), "--task", str(SEED_TASK), *runs, "--trace", "-"]
    done = _to_stdout(argv, tmp_path)
    trace = json.loads(done.stdout)
    assert trace["outcome"]["outcome"] == "success" and trace["joints"]
    assert "success" in done.stderr and "written to" not in done.stderr


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--svg", "-"], "--svg -: the picture's format comes from the file's name"),
        (["--export-trajectory", "-"], "--export-trajectory -: the format comes from the file's"),
        (["--json", "--trace", "-"], "--json and --trace - both write to standard output"),
    ],
)
def test_replay_outputs_that_cannot_share_stdout_are_refused(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    base = ["replay", str(SEED_PROGRAM), "--task", str(SEED_TASK), "--trials", "2"]
    assert main([*base, *argv]) == EXIT_USAGE
    assert capsys.readouterr().err.startswith(f"synth replay: error: {message}")
