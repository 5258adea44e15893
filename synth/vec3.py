"""Three-vector products for the referee's inner loops, without numpy's per-call overhead.

``np.cross`` normalises axes and broadcasts before it multiplies: ~17 µs for two 3-vectors on
the machines synth runs on, against ~0.6 µs for the six products written out. A replayed trial
of the seed's program takes ~30 cross products, so the difference is measurable
(benchmarks/replay.py). The products are the same IEEE operations in the same order as numpy's
(a₁b₂ − a₂b₁, a₂b₀ − a₀b₂, a₀b₁ − a₁b₀), so the result is the same floats:
tests/test_vec3.py checks it bit for bit against ``np.cross``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray


def cross3(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """The cross product a × b of two 3-vectors, as ``np.cross(a, b)`` computes it."""
    a0, a1, a2 = a.tolist()
    b0, b1, b2 = b.tolist()
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def norm3(v: NDArray[np.float64]) -> float:
    """The Euclidean norm of a float vector, as ``np.linalg.norm(v)`` computes it.

    ``np.linalg.norm`` of a 1-D float array is ``sqrt(v.dot(v))`` after its argument checks
    (~3 µs); the same dot product and a correctly rounded square root give the same float.
    """
    return math.sqrt(v.dot(v))
