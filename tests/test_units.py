"""The unit constants of synth/units.py, each checked against pint's own conversion."""

from __future__ import annotations

import pytest

from synth.exceptions import UnitError
from synth.units import CM, DEG, INCH, MM, OZ, parse_quantity, registry


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


def test_a_kept_quantity_is_the_fresh_one_and_refusals_are_raised_each_time() -> None:
    """parse_quantity keeps the values of strings it has read (synth/units.py)."""
    first = parse_quantity("1.5 in", "length")
    assert first == pytest.approx(1.5 * INCH, rel=1e-15)  # the inch is 2.54 cm exactly
    assert parse_quantity("1.5 in", "length") == first
    for _ in range(2):  # the same text asked as another dimension is refused, every time
        with pytest.raises(UnitError, match="not a angle"):
            parse_quantity("1.5 in", "angle")
