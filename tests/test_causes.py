"""A rejection's cause is read from its wording: the wordings synth writes, each to its cause."""

from __future__ import annotations

import pytest

from synth.strategies.causes import classify, root_cause
from synth.strategies.records import Rejection

# Wordings as synth/strategies/clearance.py, grasp.py, approach.py and fine.py write them.
SWEEP = (
    "the {motion} sweeps {body} into {obstacle} (they come 1.21 cm apart; 6.79 cm are needed: "
    "0.10 cm clearance and their uncertainty; hand at (44.97, 110.72, 4.84) cm; AL moves are "
    "joint-interpolated)"
)


@pytest.mark.parametrize(
    ("reason", "cause"),
    [
        # A finger swept into an obstacle on the way to the grasp is an obstruction, not a
        # grasp the hand cannot make (it was "grasp" while "finger" was matched first).
        (
            SWEEP.format(
                motion="move from BPARK to the grasp's approach point",
                body="finger_left",
                obstacle="BLK",
            ),
            "collision",
        ),
        (
            SWEEP.format(
                motion="move from BPARK to the grasp's approach point", body="palm", obstacle="BLK"
            ),
            "collision",
        ),
        # A tap's sweep was "tap" (the word in its motion's name).
        (SWEEP.format(motion="tap on PLATET", body="PIN1", obstacle="FIXTURE"), "collision"),
        (
            "every φ is obstructed; the quickest: "
            + SWEEP.format(motion="transport", body="finger_right", obstacle="PLATE"),
            "collision",
        ),
        # The grasp's own geometric checks stay grasp problems.
        (
            "pin may be 0.61 cm across from the finger pads' centres, the pads reach 0.50 cm "
            "(CENTER registers the hand along the fingers only)",
            "grasp",
        ),
        (
            "the fingers may close 0.40 cm off the grasp distance 3.54 cm, off the pin's shaft "
            "(0.40–8.00 cm from the tip)",
            "grasp",
        ),
        (
            "error footprint ±5.3 cm × ±5.3 cm against Δr_ok = 0.525 cm needs a search of about "
            "3e+04 points (more than 20000)",
            "footprint",
        ),
        ("replay proof failed: 8 of 10 trials succeeded", "proof"),
        ("no arm solution at the grasp's approach point", "reach"),
    ],
)
def test_each_wording_names_its_cause(reason: str, cause: str) -> None:
    assert classify(reason) == cause


def test_a_finger_sweep_at_pickup_is_a_root_cause_trying_harder_may_help() -> None:
    finger = SWEEP.format(
        motion="move from BPARK to the grasp's approach point", body="finger_left", obstacle="BLK"
    )
    rejections = [
        Rejection("ω=0° γ=100°", "no arm solution at the grasp's approach point", stage="pickup"),
        Rejection("ω=225° γ=100°", finger, stage="pickup"),
        Rejection("ω=270° γ=100°", finger, stage="pickup"),
    ]
    root = root_cause(rejections)
    assert (root.cause, root.count, root.of) == ("collision", 2, 3)
    assert root.helped_by_trying_harder  # keeping every ω may find one whose path is clear


def test_a_proof_that_refuted_dr_ok_gives_way_to_the_candidates_planned_without_it() -> None:
    # the stage order alone would name the proof (it got furthest); but its miss refuted the
    # task's Δr_ok and every candidate was planned again at the lead, where the search is too
    # long: that is why the task cannot be done (a random Panda variant of the seed cell)
    too_long = (
        "error footprint ±2.51 cm × ±2.36 cm: its search of 4021 points may take 1255 s with the "
        "rest of the program, more than the 600 s of simulated time a replayed run may take"
    )
    rejections = [
        Rejection("ω=0° γ=135° at the lead", too_long, stage="refine"),
        Rejection("ω=0° γ=180° at the lead", too_long, stage="refine"),
        Rejection(
            "ω=0° γ=135°",
            "replay proof failed: 2 of 4 trials succeeded",
            stage="proof",
            refuted="dr_ok",
        ),
    ]
    root = root_cause(rejections)
    assert (root.cause, root.stage, root.count, root.of) == ("footprint", "refine", 2, 2)
    # a refuted proof with nothing planned after it is still the reason
    assert root_cause(rejections[2:]).cause == "proof"
