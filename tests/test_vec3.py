"""synth.vec3.cross3 is np.cross for 3-vectors, to the bit (the referee's outcomes depend on it)."""

from __future__ import annotations

import numpy as np

from synth.vec3 import cross3, norm3


def test_cross3_is_np_cross_bit_for_bit() -> None:
    # Magnitudes over twelve decades and signed zeros: the replay's levers (~1 m), velocities
    # (~0.1 m/s) and sampled errors (~1e-4 m) all pass through it.
    rng = np.random.default_rng(20261203)
    scale = 10.0 ** rng.uniform(-6.0, 6.0, size=(20_000, 1))
    a = rng.normal(size=(20_000, 3)) * scale
    b = rng.normal(size=(20_000, 3))
    a[::7, 1] = -0.0
    b[::5, 2] = 0.0
    for x, y in zip(a, b, strict=True):
        assert cross3(x, y).tobytes() == np.cross(x, y).tobytes()


def test_cross3_of_the_axes_is_right_handed() -> None:
    x, y, z = np.eye(3)
    assert np.array_equal(cross3(x, y), z)
    assert np.array_equal(cross3(y, z), x)
    assert np.array_equal(cross3(z, x), y)
    assert np.array_equal(cross3(y, x), -z)


def test_norm3_is_np_linalg_norm_bit_for_bit() -> None:
    # the same magnitudes, and the non-finite and zero vectors the contact code guards against
    rng = np.random.default_rng(20261207)
    scale = 10.0 ** rng.uniform(-6.0, 6.0, size=(20_000, 1))
    vectors = [
        *(rng.normal(size=(20_000, 3)) * scale),
        np.zeros(3),
        np.array([-0.0, 0.0, -0.0]),
        np.array([np.inf, 1.0, 0.0]),
        np.array([np.nan, 1.0, 0.0]),
    ]
    for v in vectors:
        assert np.float64(norm3(v)).tobytes() == np.float64(np.linalg.norm(v)).tobytes()
