"""The unit constants of synth/units.py, each checked against pint's own conversion."""

from __future__ import annotations

import pytest

from synth.units import CM, DEG, INCH, MM, OZ, registry


@pytest.mark.parametrize(
    ("constant", "quantity", "si"),
    [
        (MM, "1 mm", "m"),
        (CM, "1 cm", "m"),
        (INCH, "1 inch", "m"),
        (DEG, "1 degree", "rad"),
        (OZ, "1 force_ounce", "N"),
    ],
)
def test_each_constant_is_pints_conversion(constant: float, quantity: str, si: str) -> None:
    assert constant == pytest.approx(registry().Quantity(quantity).to(si).magnitude, rel=1e-15)
