"""Seeds: the range synth takes, and how a run's seed becomes each trial's random streams.

Light on purpose (numpy only): the CLI's argument parser and the service's schemas import it
before any model is built.
"""

from __future__ import annotations

import numpy as np

__all__ = ["MAX_SEED", "trial_seed"]

MAX_SEED = 2**32 - 1
"""The largest seed synth takes, on the CLI and the service alike: a 32-bit word, which every
JSON client carries exactly (a double holds integers to 2⁵³); a seed a client could round
would not reproduce its run."""


def trial_seed(seed: int, index: int) -> np.random.SeedSequence:
    """The seed sequence of trial ``index``: child ``index`` of ``SeedSequence(seed)``."""
    return np.random.SeedSequence(seed, spawn_key=(index,))
