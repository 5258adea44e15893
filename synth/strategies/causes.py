"""Why a task has no strategy: each rejection's cause, and the root cause of a refusal.

Every rejection falls under one cause (:data:`CAUSES`). A refusal's root cause is read from
the candidates that got furthest: the planning stages run pickup → approach → refine → proof
(:data:`STAGES`), and a candidate dropped at a later stage passed every earlier check, so its
reason says more about the task than the many candidates that fell at the first hurdle. Among
the rejections of the deepest stage the most frequent cause wins (ties: the first, which is the
best-ranked candidate). ``pruned`` rejections (ω the seed's rating discarded, L2122) never name
the root cause: they are a search limit, not a property of the task. Nor do proofs that refuted
the planner's belief (a trial that missed the hole, a Δr_ok wider than the parts' lead) where
candidates were planned again without it: the re-planned candidates' reasons are the task's.
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from synth.strategies.records import Rejection

__all__ = ["CAUSES", "STAGES", "RootCause", "classify", "root_cause"]

CAUSES: dict[str, str] = {
    "fit": "the pin cannot enter the hole (fit, jamming or wedging)",
    "reach": "the arm cannot reach the poses the task needs",
    "collision": "every motion the task needs is obstructed",
    "grasp": "the hand cannot grasp the pin where it may be",
    "tilt": "the pin's tilt at the hole may exceed what the insertion tolerates",
    "depth": "the hole's height is too uncertain for a guarded insertion",
    "tap": "no tap can reduce the height error enough",
    "footprint": "the position error is too large for a search",
    "proof": "the program failed its replay proof",
    "pruned": "grasp orientations discarded by the seed's rating",
    "other": "the planner's checks",
}
"""Cause keyword → what it means, in plain words."""

STAGES: tuple[str, ...] = ("pickup", "approach", "refine", "proof")
"""Planning stages in the order a candidate meets them."""

_PATTERNS: tuple[tuple[str, re.Pattern[str]], ...] = tuple(
    (cause, re.compile(pattern, re.IGNORECASE))
    for cause, pattern in (
        ("pruned", r"^pruned:"),
        ("proof", r"\breplay\b|\bproof\b"),
        # A gross motion's sweep names the moving body, which may be a finger or the tapping
        # pin: the sweep itself is the cause, whatever the words it names (clearance.py).
        ("collision", r"\bsweeps \S+ into\b|\bobstructed\b"),
        ("fit", r"does not fit|\bjam|\bwedg"),
        ("tilt", r"\btilt\b"),
        ("footprint", r"error footprint|search of about"),
        ("tap", r"\btap"),
        ("depth", r"Δz|standoff|dtry"),
        ("grasp", r"opening|grasp distance|finger|pad\b|CENTER"),
        ("collision", r"obstruct|sweeps?|collid|\binto\b|apart"),
        ("reach", r"no arm solution|out of reach|unreachable|joint limit|no φ"),
    )
)


def classify(reason: str) -> str:
    """The cause a rejection's wording names (:data:`CAUSES`; ``other`` when none does)."""
    for cause, pattern in _PATTERNS:
        if pattern.search(reason):
            return cause
    return "other"


@dataclass(frozen=True)
class RootCause:
    """A refusal's root cause.

    ``cause`` is the keyword, ``stage`` where it struck, ``count`` of ``of`` of the stage's
    rejections share it, and ``example`` is the first of them.
    """

    cause: str
    stage: str | None
    count: int
    of: int
    example: Rejection | None

    @property
    def helped_by_trying_harder(self) -> bool:
        """Whether keeping every ω could help: only for reach, collision and proof failures."""
        return self.cause in ("reach", "collision", "proof")

    def sentence(self) -> str:
        """``<plain cause> (3 of 4 candidates at <stage>): <first reason>``."""
        plain = CAUSES.get(self.cause, self.cause)
        if self.example is None:
            return f"{plain}: no candidate strategy was generated"
        where = f" at {self.stage}" if self.stage else ""
        share = f"{self.count} of {self.of} candidates{where}"
        return f"{plain} ({share}): {self.example.candidate}: {self.example.reason}"


def root_cause(rejections: Sequence[Rejection]) -> RootCause:
    """The root cause of a refusal (see the module docstring)."""
    counted = [r for r in rejections if r.kind != "pruned"]
    # A proof that refuted a belief (a miss: Δr_ok wider than the lead) was followed by
    # candidates planned without it; theirs are the task's reasons, the refuted one is not.
    unrefuted = [r for r in counted if r.refuted is None]
    if unrefuted and len(unrefuted) < len(counted):
        counted = unrefuted
    if not counted:
        example = rejections[0] if rejections else None
        return RootCause("other" if example is None else example.kind, None, 0, 0, example)
    depth = {stage: k for k, stage in enumerate(STAGES)}
    deepest = max(depth.get(r.stage or "", -1) for r in counted)
    at_stage = [r for r in counted if depth.get(r.stage or "", -1) == deepest]
    tally = Counter(r.kind for r in at_stage)
    best = max(tally.values())
    first = next(r for r in at_stage if tally[r.kind] == best)
    return RootCause(first.kind, first.stage, best, len(at_stage), first)
