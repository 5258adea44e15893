"""The seated hand's displacement box that the get-clear is checked over (synth.strategies.fine).

Oracle: Monte Carlo through the replay. In each sampled world the arm's joints where it lets go
of the seated pin (the trace's samples, the replay's own states) put the hand, by the arm's
kinematics, somewhere near its nominal seat; the planner's box (:func:`seat_displacements`)
claims every such place lies within the footprint widened by the hand's error, whatever the
hole's own error (it cancels: the search and the guarded move follow the true hole).
"""

from __future__ import annotations

import numpy as np
import pytest
from _paths import SEED_TAP_TASK, SEED_TASK
from _tasks import synthesized

from synth.replay.run import replay_context
from synth.replay.trace import record_run
from synth.strategies.context import plan_context
from synth.strategies.fine import seat_displacements


def _let_go_joints(context, trial: int | None) -> np.ndarray | None:
    """The arm's joints as the last OPEN (the let-go) starts; None if the run failed."""
    trace = record_run(context, trial=trial, seed=0)
    if trace.report.outcome != "success":
        return None  # the seed's one miss in 1 000 (trial 52): no seat to measure
    opens = [s for s in trace.samples if s.motion == "open"]
    last_line = opens[-1].line
    return np.array(next(s for s in opens if s.line == last_line).q)


@pytest.mark.parametrize("task", [SEED_TASK, SEED_TAP_TASK], ids=["search", "tap"])
def test_the_seated_hand_stays_within_its_displacement_box(task) -> None:
    synthesis = synthesized(task)
    strategy = synthesis.strategy
    ctx = plan_context(synthesis.task, None, task.parent, None)
    displacements = seat_displacements(ctx, strategy)
    corners = np.array(
        [c.translation for _, c in displacements if np.allclose(c.rotation, np.eye(3))]
    )
    turns = [c for _, c in displacements if not np.allclose(c.rotation, np.eye(3))]
    # 8 corners of a box and a turn either way about each axis by the hand's ±0.25°
    assert len(corners) == 8 and len(turns) == 6
    # the corners are a box's: its frame is the hole's turned by ζ (the footprint's), half-sides
    # the largest |corner| along each of its axes
    footprint = strategy.errors
    assert footprint is not None
    c, s = np.cos(footprint.zeta), np.sin(footprint.zeta)
    box = ctx.world_hole.rotation @ np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    half = np.max(np.abs(corners @ box), axis=0)
    hand = 0.05 * 0.0254  # the seed's hand error, ±0.05 in on each axis
    assert half == pytest.approx(np.array([footprint.dx, footprint.dy, footprint.dz]) + hand)

    context = replay_context(synthesis.program, synthesis.task)
    arm = context.arm
    q_nominal = _let_go_joints(context, None)
    assert q_nominal is not None
    nominal = arm.forward(q_nominal).translation
    reached = []
    for trial in range(60):
        q = _let_go_joints(context, trial)
        if q is not None:
            reached.append(np.abs((arm.forward(q).translation - nominal) @ box) / half)
    reached = np.array(reached)
    # within the box in every trial (1 µm for the guarded stop's resolution) …
    assert np.all(reached <= 1.0 + 1e-6 / half.min())
    # … and the box is not vacuous: lateral displacements reach a good part of it
    assert reached[:, :2].max() > 0.3
