"""The goal verdict of an insertion: the pin let go, seated in its hole, the hand clear.

:func:`goal_verdict` holds when the insertion's pin is not held, stands in the target hole at
its seated depth (within ``seat_tolerance``, :func:`~synth.replay.capture.seat_depth`), and no
palm or finger is within ``clear_distance`` of it (Coal distances at the arm's configuration,
of those pairs only).
Otherwise it says why not.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from synth.models.arm import HAND_BODIES, CollisionScene
from synth.models.workcell import HoleSite
from synth.replay.capture import seat_depth
from synth.replay.cell import PinState, ReplayOptions
from synth.replay.sweeps import pair_distances

__all__ = ["goal_verdict"]


def goal_verdict(
    state: PinState,
    target: HoleSite,
    scene: Callable[[], CollisionScene],
    q: NDArray[np.float64],
    options: ReplayOptions,
) -> tuple[bool, str]:
    """Whether ``state``'s pin is seated in ``target``, let go, the hand clear; and why.

    ``scene()`` gives the collision scene of the hand and the free pins (built only when the
    pin is seated: the hand's clearance is the last test).
    """
    name = state.model.name
    if state.held:
        return False, f"the hand still holds {name}"
    if state.hole is None or state.hole.frame != target.frame:
        if state.hole is not None:
            return False, f"{name} is in {state.hole.name}, not in {target.name}"
        where = f"it rests on {state.rests_on}" if state.rests_on else "it is not in a hole"
        return False, f"{name} is not in {target.name}: {where}"
    seat = seat_depth(target, state.model)
    if state.depth < seat - options.seat_tolerance:
        return False, (
            f"{name} is only {100 * state.depth:.2f} cm into {target.name} "
            f"(seated: {100 * seat:.2f} cm)"
        )
    cell = scene()
    pairs = [
        k
        for k, (a, b) in enumerate(cell.pairs)
        if name in (a, b) and (a in HAND_BODIES or b in HAND_BODIES)
    ]
    near = pair_distances(cell, q, pairs)
    if near and min(near) < options.clear_distance:
        return False, f"the hand is not clear of {name} ({100 * min(near):.2f} cm)"
    return True, f"{name} seated in {target.name}"
