"""The plan picture (``synth plan --svg``): elements present and in place, read back from the SVG.

Oracles: the search pattern recomputed from the seed's rule (L2743–2770: step = 0.75·Δr_ok,
rings R = k·step, points every step/R rad from 0 while < 2π, kept when |x| ≤ Δx and |y| ≤ Δy,
turned by ζ), the seed's printed ring step (R = .572 cm, L2743) and ring count (R ≤ 1.72,
L2753), the footprint's definition (a box ±Δx × ±Δy turned by ζ), and the strategy's heights.
"""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest
from _paths import ROOT, SEED_TAP_TASK, SEED_TASK
from _svg import SvgFigure
from _tasks import synthesized

from synth.cli import main
from synth.pictures.plan import draw_plan, plan_picture
from synth.pictures.render import figure_bytes
from synth.pipeline import Synthesis

CM = 100.0
NUMBER = re.compile(r"(?<![A-Za-z_\d])[-+−]?\d+(?:\.\d+)?(?![A-Za-z_\d])")


@pytest.fixture(scope="module")
def seed() -> Synthesis:
    return synthesized(SEED_TASK)


@pytest.fixture(scope="module")
def tap() -> Synthesis:
    return synthesized(SEED_TAP_TASK)


def svg_of(result: Synthesis) -> SvgFigure:
    return SvgFigure(figure_bytes(draw_plan(plan_picture(result.strategy, result.graph))))


def seed_rule_points(dr_ok: float, rings: int, dx: float, dy: float, zeta: float) -> np.ndarray:
    """The program's search offsets in the hole frame, in the order it tries them [m]."""
    step = 0.75 * dr_ok
    out = [(0.0, 0.0)]  # the first attempt, at the hole
    for k in range(1, rings + 1):
        radius, w = k * step, 0.0
        while w < 2 * math.pi:
            x, y = radius * math.cos(w), radius * math.sin(w)
            if abs(x) <= dx and abs(y) <= dy:
                out.append(
                    (
                        x * math.cos(zeta) - y * math.sin(zeta),
                        x * math.sin(zeta) + y * math.cos(zeta),
                    )
                )
            w += step / radius
    return np.array(out)


def test_search_points_are_the_programs_in_its_order(seed: Synthesis) -> None:
    search = seed.strategy.search
    assert search is not None
    assert search.step == pytest.approx(0.00572, abs=1e-5)  # L2743: R = .572 cm
    assert search.rings == 3  # L2753: WHILE R ≤ 1.72
    svg = svg_of(seed)
    drawn = svg.to_data("top-view", svg.uses("search-points"))
    expected = CM * seed_rule_points(seed.strategy.dr_ok, 3, search.dx, search.dy, search.zeta)
    assert drawn.shape == expected.shape
    np.testing.assert_allclose(drawn, expected, atol=2e-3)  # [cm]
    for k in (1, 2, 3):
        assert svg.has(f"search-ring-{k}")
    assert not svg.has("search-ring-4")


def test_footprints_are_boxes_of_the_certified_and_first_order_bounds(seed: Synthesis) -> None:
    errors = seed.strategy.errors
    assert errors is not None
    svg = svg_of(seed)
    for gid, (dx, dy, zeta) in (
        ("footprint-certified", (errors.dx, errors.dy, errors.zeta)),
        ("footprint-first-order", tuple(errors.first_order[k] for k in ("dx", "dy", "zeta"))),
    ):
        corners = svg.to_data("top-view", svg.path_points(gid))[:4] / CM
        along = corners @ np.array([math.cos(zeta), math.sin(zeta)])
        across = corners @ np.array([-math.sin(zeta), math.cos(zeta)])
        np.testing.assert_allclose(np.sort(np.abs(along)), [dx] * 4, atol=2e-5)
        np.testing.assert_allclose(np.sort(np.abs(across)), [dy] * 4, atol=2e-5)
    # the seed's footprint 1.58 × 1.15 cm (L2437) lies inside the certified one
    assert errors.dx >= 0.0158 and errors.dy >= 0.0115


def test_top_view_shows_the_outline_the_holes_and_phi(seed: Synthesis) -> None:
    svg = svg_of(seed)
    for name in ("BH1", "BH2", "BH3", "BH4"):
        assert svg.has(f"hole-{name}")
    outline = svg.to_data("top-view", svg.path_points("outline"))[:4]
    # BH1 sits at (3.85, 3.20) cm in a box of half-sides 4.45 × 3.80 cm (fixture, L2576)
    np.testing.assert_allclose(outline.min(axis=0), [-4.45 - 3.85, -3.80 - 3.20], atol=2e-3)
    np.testing.assert_allclose(outline.max(axis=0), [4.45 - 3.85, 3.80 - 3.20], atol=2e-3)
    arrow = svg.to_data("top-view", svg.path_points("approach-phi"))
    direction = arrow[-1] - arrow[0]
    assert math.atan2(direction[1], direction[0]) == pytest.approx(seed.strategy.phi, abs=0.05)
    assert not svg.has("tap-place")


def test_tap_task_draws_the_tapping_place_and_no_search(tap: Synthesis) -> None:
    strategy = tap.strategy
    assert strategy.tap is not None and strategy.search is None
    svg = svg_of(tap)
    place = svg.to_data("top-view", svg.uses("tap-place"))
    np.testing.assert_allclose(place[0], CM * np.array(strategy.tap.offset[:2]), atol=2e-3)
    assert not svg.has("search-points")
    assert svg.has("tap-ring")
    # the place is on the surface: inside the outline drawn
    outline = svg.to_data("top-view", svg.path_points("outline"))[:4]
    assert np.all(place[0] > outline.min(axis=0)) and np.all(place[0] < outline.max(axis=0))
    band = svg.to_data("side-view", svg.path_points("dz-band-after-tap"))
    np.testing.assert_allclose(np.ptp(band[:, 1]) / 2, CM * strategy.tap.dz_after, atol=2e-3)
    assert strategy.tap.dz_after < strategy.errors.dz  # the tap is why Δz shrinks (§4.5.2)
    tap_via = svg.to_data("side-view", svg.path_points("height-tap-via"))
    assert tap_via[0, 1] == pytest.approx(2 * 2.54, abs=2e-3)  # 2 in above the surface (L2852)


def test_side_view_heights_are_the_strategys(seed: Synthesis) -> None:
    s = seed.strategy
    svg = svg_of(seed)
    for gid, z in (
        ("height-surface", 0.0),
        ("height-approach", s.standoff),
        ("height-seat", -s.d_f),
        ("height-dtry", -s.dtry),
    ):
        line = svg.to_data("side-view", svg.path_points(gid))
        assert line[0, 1] == pytest.approx(CM * z, abs=2e-3), gid
    assert s.d_f == pytest.approx(0.0171)  # d_f = 1.71 cm (L2566)
    assert s.dtry == pytest.approx(0.0171 + 0.0254, abs=1e-4)  # d_f + 1 in (L2188)


def test_every_label_carries_its_unit(seed: Synthesis, tap: Synthesis) -> None:
    for result in (seed, tap):
        svg = svg_of(result)
        for gid in ("top-view", "side-view"):
            ticks = {
                "".join(t.itertext())
                for g in svg.group(gid).iter()
                if (g.get("id") or "").startswith(("xtick", "ytick"))
                for t in g.iter("{http://www.w3.org/2000/svg}text")
            }
            labels = [t for t in svg.texts(gid) if t not in ticks]
            # a quantity: a number not inside a name (BH1) and not a search-order index
            numbered = [t for t in labels if NUMBER.search(t) and not t.isdigit()]
            assert len(numbered) >= 4
            for text in numbered:
                assert "cm" in text or "°" in text, text


def test_cli_writes_svg_and_png(tmp_path: Path) -> None:
    svg, png = tmp_path / "plan.svg", tmp_path / "out" / "plan.png"
    task = str(SEED_TASK)
    assert main(["plan", task, "--proof-trials", "0", "--workers", "1", "--svg", str(svg)]) == 0
    assert SvgFigure(svg.read_bytes()).has("search-points")
    assert main(["plan", task, "--proof-trials", "0", "--workers", "1", "--svg", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["plan", task, "--svg", str(tmp_path / "plan.pdf")]) == 2


def test_the_readme_picture_is_the_seeds_plan(seed: Synthesis) -> None:
    committed = SvgFigure((ROOT / "docs" / "img" / "seed_4_8_plan.svg").read_bytes())
    drawn = committed.to_data("top-view", committed.uses("search-points"))
    expected = CM * plan_picture(seed.strategy, seed.graph).search_points
    np.testing.assert_allclose(drawn, expected, atol=2e-3)


@pytest.mark.parametrize("name", ["$\\foo$", "$x^$", "cost $5 and $6"])
def test_a_task_name_with_dollars_is_drawn_as_written(seed: Synthesis, name: str) -> None:
    # Matplotlib reads text between two $ as mathtext: "$\foo$" and "$x^$" failed to draw
    # (a 500 from the service, exit 70 from the CLI; the service hunt) and "cost $5 and $6"
    # came out as "cost 5 6: plan … and"
    picture = dataclasses.replace(plan_picture(seed.strategy, seed.graph), task=name)
    titles = [t for t in SvgFigure(figure_bytes(draw_plan(picture))).texts() if ": plan " in t]
    assert titles == [f"{name}: plan {seed.strategy.name}"]


def test_a_sequences_picture_names_its_step_and_the_service_finds_its_strategy() -> None:
    # A sequence's picture draws its first step: it did not say so, and the service, reading
    # a strategy name the sequence's stored result does not have, re-ran the plan's whole
    # proof on every request (10 s for two steps at 20 trials; the service hunt)
    from server.pictures import pictured_strategy
    from synth.pipeline import SynthesisOptions, synthesize
    from synth.replay.proof import ProofOptions

    task = ROOT / "fixtures" / "tasks" / "plate_two_pins_shim.yaml"
    options = SynthesisOptions(proof=ProofOptions(trials=0, workers=1))
    result = synthesize(task, options)
    strategy, graph, step = result.pictured
    assert step == "step 1 of 2 (PIN1 into PH1)"
    picture = plan_picture(strategy, graph, step)
    titles = [t for t in SvgFigure(figure_bytes(draw_plan(picture))).texts() if ": plan " in t]
    assert titles == [f"plate_two_pins_shim, step 1 of 2 (PIN1 into PH1): plan {strategy.name}"]
    assert pictured_strategy(result.to_json()) == strategy.name
    single = synthesized(SEED_TASK)
    assert pictured_strategy(single.to_json()) == single.pictured[0].name
