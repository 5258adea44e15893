"""The unit constants of synth/units.py, each checked against pint's own conversion."""

from __future__ import annotations

import math

import pytest

from synth.exceptions import UnitError
from synth.units import CM, DEG, INCH, MM, OZ, Dimension, parse_quantity, registry


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
        with pytest.raises(UnitError, match="is not an angle: in measures a length"):
            parse_quantity("1.5 in", "angle")


@pytest.mark.parametrize(
    ("text", "dim", "message"),
    [
        # pint counts an angle as dimensionless ("its dimension is dimensionless" was the message)
        (
            "0.82 deg",
            "length",
            "'0.82 deg' is not a length: deg measures an angle; write a length, e.g. '0.82 cm'",
        ),
        (
            "0.3 cm",
            "angle",
            "'0.3 cm' is not an angle: cm measures a length; write an angle, e.g. '0.3 deg'",
        ),
        ("2 s", "force", "'2 s' is not a force: s measures a time; write a force, e.g. '2 N'"),
        ("1 N*m", "mass", "'1 N*m' is not a mass: N*m measures a torque"),
    ],
)
def test_a_quantity_of_the_wrong_kind_names_what_its_unit_measures(
    text: str, dim: Dimension, message: str
) -> None:
    with pytest.raises(UnitError) as refused:
        parse_quantity(text, dim)
    assert str(refused.value).startswith(message)


def test_a_number_that_is_not_finite_is_refused_as_such() -> None:
    # JSON's 1e999 arrives as inf: "inf has no unit; write … e.g. 'inf cm'" suggested a value
    # that is itself refused
    for value in (float("inf"), float("-inf"), float("nan"), 10**400):
        with pytest.raises(UnitError, match="is not a finite number"):
            parse_quantity(value, "length")
    with pytest.raises(UnitError, match="has no unit"):
        parse_quantity(1e308, "length")


@pytest.mark.parametrize(
    ("text", "dim"),
    [
        ("2 bit", "angle"),  # was read as 2 rad (114.6°): pint counts the bit dimensionless
        ("1 count", "angle"),
        ("3 sr", "angle"),  # a solid angle, rad²
        ("5 m*rad", "length"),  # was read as 5 m
        ("5 cm/rad", "length"),
    ],
)
def test_a_dimensionless_unit_that_is_not_the_dimensions_own_is_refused(
    text: str, dim: Dimension
) -> None:
    with pytest.raises(UnitError, match=f"is not a unit of {dim}"):
        parse_quantity(text, dim)


@pytest.mark.parametrize(
    ("text", "dim", "si"),
    [
        ("1 turn", "angle", 2 * math.pi),
        ("3 arcmin", "angle", math.radians(3 / 60)),
        ("100 gradian", "angle", math.pi / 2),
        ("8 oz", "force", 8 * 0.028349523125 * 9.80665),  # a weight, as AL writes forces
        ("3 ft*lbf", "torque", 3 * 0.3048 * 0.45359237 * 9.80665),
    ],
)
def test_the_dimensions_own_units_still_read(text: str, dim: Dimension, si: float) -> None:
    assert parse_quantity(text, dim) == pytest.approx(si, rel=1e-12)


def test_units_that_cancel_are_named_and_the_example_is_a_valid_quantity() -> None:
    # Hunt A: '5 rad/rad' suggested "e.g. '5 rad/rad deg'", itself refused
    with pytest.raises(UnitError) as refused:
        parse_quantity("5 rad/rad", "angle")
    message = str(refused.value)
    assert message == (
        "'5 rad/rad' has no unit: rad/rad cancels out; write it with a unit of angle, e.g. '5 deg'"
    )
    suggested = message.rsplit("e.g. ", 1)[1].strip("'")
    assert parse_quantity(suggested, "angle") == pytest.approx(math.radians(5))
    with pytest.raises(UnitError, match=r"cm/mm cancels out; .* e\.g\. '2 cm'"):
        parse_quantity("2 cm/mm", "length")


def test_threads_reading_units_at_once_share_one_registry() -> None:
    # The service checks specs in threads: 8 first reads at once each built a registry under
    # functools.cache, and a valid spec was refused with "Cannot operate with Unit and Unit of
    # different registries" (the fourth hunt, a fresh server and a burst of submissions)
    import threading

    import synth.units as units

    saved = list(units._REGISTRY)
    caches = (units._parse_text, units._root)
    try:
        units._REGISTRY.clear()
        for cached in caches:
            cached.cache_clear()
        start = threading.Barrier(8)
        seen: list[object] = []
        failures: list[BaseException] = []

        def read(k: int) -> None:
            start.wait()
            try:
                value = parse_quantity(f"{k + 1}.5 cm", "length")
                assert value == pytest.approx((k + 1.5) / 100)
                assert parse_quantity(f"{k} deg", "angle") == pytest.approx(math.radians(k))
                seen.append(units.registry())
            except BaseException as exc:  # collected: a thread's failure is not the test's
                failures.append(exc)

        threads = [threading.Thread(target=read, args=(k,)) for k in range(8)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        assert failures == []
        assert len(seen) == 8 and all(r is seen[0] for r in seen)
    finally:
        units._REGISTRY[:] = saved
        for cached in caches:
            cached.cache_clear()
