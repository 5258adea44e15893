"""Where a replayed trial's time goes: the referee's parts, per trial, on the seed's programs.

Usage: python benchmarks/replay_parts.py [--trials N] [--program NAME ...]

For the seed's search listing and synth's own program (fixtures/golden/seed_4_8.al) on
seed_4_8, trials 0 … N−1 of seed 0 run in this process (after one warm-up trial) with the
referee's parts wrapped in timers: the held pin's walk along a segment (and inside it the
contact search, by what it found, and the capture test's entry contact), the arm's sweep of a
segment, inverse kinematics, trajectory timing, and the hand's operations. Printed per part:
calls per trial, ms per trial and the share of the trial's wall time; the rest is the AL
interpreter, the timeline and the glue between the parts. The parts nest as indented (a
nested row is part of the row above it); the wrappers cost a little of their own, so the
total is a few per cent above an unwrapped run (``benchmarks/replay.py`` times those).

This is the table to read before speeding the referee up (issue: ten times faster): a part
that takes 5 % of a trial can give at most 5 %.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import synth.replay.capture as capture
import synth.replay.machine as machine
import synth.replay.walk as walk
from synth.replay import replay_context, run_trial

ROOT = Path(__file__).resolve().parent.parent
SEED = ROOT / "fixtures" / "tasks" / "seed_4_8.yaml"
PROGRAMS = {
    "seed_4_8_search.al": ROOT / "tests" / "data" / "al" / "seed_4_8_search.al",
    "golden/seed_4_8.al": ROOT / "fixtures" / "golden" / "seed_4_8.al",
}


@dataclass
class Timers:
    """Calls and seconds per part (a part's key may carry what its call found)."""

    calls: dict[str, int] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)

    def add(self, key: str, seconds: float) -> None:
        self.calls[key] = self.calls.get(key, 0) + 1
        self.seconds[key] = self.seconds.get(key, 0.0) + seconds


def _timed(
    timers: Timers, key: str, original: Callable, kind: Callable[[object], str] | None = None
) -> Callable:
    def wrapped(*args: object, **kwargs: object) -> object:
        start = time.perf_counter()
        result = original(*args, **kwargs)
        elapsed = time.perf_counter() - start
        timers.add(key, elapsed)
        if kind is not None:
            timers.add(f"{key}: {kind(result)}", elapsed)
        return result

    return wrapped


def _found(contact: object) -> str:
    return "free flight" if contact is None else str(getattr(contact, "kind", "?"))


# (owner, attribute, part, what the call found): each function is looked up where its caller
# reads it, so the wrapper is what the referee calls
_PARTS: tuple[tuple[object, str, str, Callable[[object], str] | None], ...] = (
    (machine, "walk_segment", "pin walk", None),
    (walk, "first_contact", "  contact search", _found),
    (capture, "entry_contact", "  capture test (entry contact)", None),
    (machine, "sweep_segment", "arm sweep", None),
    (machine, "solve_near", "inverse kinematics", None),
    (machine, "motion_time", "trajectory timing", None),
    (machine.ReplayMachine, "_hand_operation", "hand operations", None),
)


@contextmanager
def wrapped_parts(timers: Timers) -> Iterator[None]:
    """The referee's parts wrapped in ``timers`` while the block runs."""
    saved = [(owner, name, getattr(owner, name)) for owner, name, _, _ in _PARTS]
    for owner, name, part, kind in _PARTS:
        setattr(owner, name, _timed(timers, part, getattr(owner, name), kind))
    try:
        yield
    finally:
        for owner, name, original in saved:
            setattr(owner, name, original)


def parts_of(path: Path, trials: int) -> tuple[float, Timers]:
    """Wall seconds of ``trials`` trials of ``path`` with the parts timed, and the timers."""
    context = replay_context(path.read_text(encoding="utf-8"), SEED)
    run_trial(context, 0, 0)  # warm: meshes, hulls, kept paths
    timers = Timers()
    with wrapped_parts(timers):
        start = time.perf_counter()
        for i in range(trials):
            run_trial(context, 0, i)
        wall = time.perf_counter() - start
    return wall, timers


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=30, help="trials per program")
    parser.add_argument(
        "--program", action="append", choices=sorted(PROGRAMS), help="one program (repeatable)"
    )
    args = parser.parse_args()
    names = args.program or list(PROGRAMS)
    order = [part for _, _, part, _ in _PARTS]
    for name in names:
        wall, timers = parts_of(PROGRAMS[name], args.trials)
        trial_ms = 1000.0 * wall / args.trials
        rows = []
        for part in order:
            found = sorted(k for k in timers.calls if k.startswith(f"{part}: "))
            for key in [part, *found]:
                if key not in timers.calls:
                    continue
                label = key if key == part else f"    {key.split(': ', 1)[1]}"
                ms = 1000.0 * timers.seconds[key] / args.trials
                rows.append((label, timers.calls[key] / args.trials, ms, 100.0 * ms / trial_ms))
        top = sum(1000.0 * timers.seconds.get(p, 0.0) for p in order if not p.startswith(" "))
        rest = trial_ms - top / args.trials
        rows.append(("interpreter, timeline, glue", float("nan"), rest, 100.0 * rest / trial_ms))
        print(f"{name}: {args.trials} trials, {trial_ms:,.1f} ms a trial (wrapped)")
        width = max(len(r[0]) for r in rows)
        print(f"  {'part':<{width}}  {'calls':>6}  {'ms':>7}  {'share':>6}")
        for label, calls, ms, share in rows:
            shown = "" if calls != calls else f"{calls:6.2f}"  # NaN: not a part of its own
            print(f"  {label:<{width}}  {shown:>6}  {ms:7.2f}  {share:5.1f}%")


if __name__ == "__main__":
    main()
