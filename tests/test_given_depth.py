"""A given d_f must agree with where the pin seats (``refuse_unprovable``).

The replay pushes a pin into its hole until it bottoms out, at the derived d_f (the hole's
depth, or the pin's length less its tip taper). The program's success test reads the pin's
depth against the d_f it was planned with: a d_f given shallower than the seat by more than
the test's least margin over a seated reading (the reading floor, 0.01 in) makes a seated pin
read as a miss. Found by a task hunt: a 0.8 cm d_f for a 2 cm hole was planned, every
candidate failed its nominal replay, and the refusal blamed the first candidate's pickup.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from _paths import SEED_TASK

import synth.strategies.context as context
from synth.exceptions import NoStrategyError, SpecError
from synth.models.loader import load_task
from synth.models.spec import TaskSpec
from synth.pipeline import SynthesisOptions, synthesize
from synth.replay.proof import ProofOptions
from synth.strategies.context import plan_context
from synth.strategies.options import PlanOptions

FLOOR = PlanOptions().reading_floor  # 0.01 in: the arm's reading resolution (L3385)


def _given(d_f: str) -> str:
    text = SEED_TASK.read_text(encoding="utf-8")
    given = "  d_f: 1.71 cm "  # measured by the seed (L2582–2585), the depth of BH1
    assert given in text
    return text.replace(given, f"  d_f: {d_f} ")


def _task(tmp_path: Path, d_f: str) -> TaskSpec:
    path = tmp_path / "task.yaml"
    path.write_text(_given(d_f), encoding="utf-8")
    return load_task(path)


def test_a_d_f_shallower_than_the_seat_is_refused_at_its_field(tmp_path: Path) -> None:
    with pytest.raises(SpecError) as info:
        plan_context(_task(tmp_path, "0.8 cm"))
    refusal = info.value
    assert refusal.path == "insertion.d_f"
    assert refusal.line is not None
    line = _given("0.8 cm").splitlines()[refusal.line - 1]
    assert line.split("#")[0].strip() == "d_f: 0.8 cm"
    # BH1 is 1.71 cm deep and the pin reaches 2 in − 0.34 cm = 4.74 cm: the hole stops it
    assert "shallower than where PIN1 seats in BH1: 1.71 cm, the hole's depth" in refusal.detail
    assert "a seated pin would read 0.91 cm off" in refusal.detail


def test_a_d_f_within_the_reading_floor_of_the_seat_is_planned(tmp_path: Path) -> None:
    # 0.02 cm short is inside the 0.0254 cm the success test keeps over a seated reading
    ctx = plan_context(_task(tmp_path, "1.69 cm"))
    assert ctx.insertion.d_f == pytest.approx(0.0169)
    assert ctx.insertion.seat - ctx.insertion.d_f < FLOOR
    with pytest.raises(SpecError):  # 0.03 cm short is outside it
        plan_context(_task(tmp_path, "1.68 cm"))


def test_without_the_refusal_every_program_fails_its_nominal_replay(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # The refusal's premise, checked by the referee: with the check turned off, each candidate
    # planned for d_f = 0.8 cm aborts in the believed world, its seated pin read as a miss.
    monkeypatch.setattr(context, "refuse_unprovable", lambda *args, **kwargs: None)
    path = tmp_path / "task.yaml"
    path.write_text(_given("0.8 cm"), encoding="utf-8")
    with pytest.raises(NoStrategyError) as info:
        synthesize(path, SynthesisOptions(proof=ProofOptions(trials=0, workers=1)))
    proofs = [r for r in info.value.rejections if r.stage == "proof"]
    assert proofs, info.value
    assert all("nominal replay failed" in r.reason and "MISSED BH1" in r.reason for r in proofs)
