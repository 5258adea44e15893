"""The replay's capture decision against Coal on a chamfered-hole mesh.

:func:`synth.replay.capture.captures` decides from the parts' exact profiles where a pin let
down along the hole's axis first touches: chamfer or bore (captured), the face around the mouth
(not), or the mouth's rim (captured if the rim pushes it inwards more than μ times as hard as it
holds it up). The oracle here is Coal on meshes built independently of that computation: the
seed's box with BH1 (⌀0.64 cm, 1.71 cm deep, 0.25 cm chamfer; 256 sections) and, to tell the
face from the rest, the same box with a plain through hole of the mouth's radius, whose top
face is exactly the face around the mouth; the seed's pin (⌀0.635 cm, 0.34 cm taper to a
0.13 cm tip; 128 sections, Coal's hull refuses more). Each placement is dropped onto both by
bisection on Coal collisions (to 10⁻¹¹ m):

* the chamfered box touched first (by more than 2 µm): a mouth contact, captured;
* else Coal's witness point on the box just before the contact: beyond the mouth's radius, the
  face (not captured); below the top face, the chamfer (captured); on the rim, the direction of
  Coal's normal decides as the rule says (μ = 0.3), its median over five distances before the
  contact (an edge of one polygon meeting an edge of the other can meet at a vertex).

Left out are the placements where the decision itself changes within 3 µm of lateral offset or
10⁻⁴ rad of tilt (the meshes' polygons lie within 0.4 µm of the circles), and rim contacts whose
Coal slope lies within 0.05 of μ. The default grid (6 offsets 0–0.6 cm × 4 tilts 0°–30° × 3
leans) decides 69 of 72 placements (35 mouth, 22 face, 12 rim), all as Coal does. The slow full
grid (13 offsets 0–0.7 cm × 8 tilts 0°–40° × 5 leans, 520 placements) decides 496 (236 mouth,
145 face, 115 rim), all as Coal does; 24 are left out.

The closed form the replay used before (``lateral + a cos θ ≤ r_m`` and
``θ ≤ atan((r_m − a)/(h + w))`` = 36.7°, the planner's Δr_ok and Δθ_ok) agrees with this on
every decided placement tilted 3° or less; tilted 10°–40° it refused 66 of the full grid's
decided placements that Coal and the geometry capture (tilted tips whose lowest edge reaches
the chamfer, or whose taper reaches the rim, from beyond the upright lead; and every placement
at 40°), and it never captured one they refuse.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable

import coal
import numpy as np
import pinocchio as pin
import pytest
from _paths import SEED_TASK

from synth.models import meshes
from synth.models.arm.collision import coal_geometry, convex_hull
from synth.models.graph import AttributeGraph
from synth.models.loader import load_task
from synth.models.workcell import HoleSite, PinModel, WorkcellModel
from synth.replay.capture import TipPlacement, captures, entry_contact
from synth.replay.truth import nominal_world

CM = 0.01
MU = 0.3
HEIGHT = 1.5 * CM  # the tip centre's start above the mouth: clear of everything
BOX = (3 * CM, 3 * CM, 2.5 * CM)


@pytest.fixture(scope="module")
def parts() -> tuple[HoleSite, PinModel]:
    graph = AttributeGraph(load_task(SEED_TASK))
    cell = WorkcellModel(graph, [np.array([0.2, 0.7, 0.0])]).place(nominal_world(graph))
    return cell.hole("bh1"), cell.pins["pin1"]


class CoalDrop:
    """The pin let down onto the chamfered box and onto the face-only box, by Coal."""

    def __init__(self, hole: HoleSite, model: PinModel) -> None:
        r, w, depth = hole.radius, hole.chamfer, hole.depth
        self.mouth = r + w
        self.real = coal_geometry(meshes.box_with_holes(BOX, [(0, 0, 2 * r, depth, w)], 256))
        self.face = coal_geometry(
            meshes.box_with_holes(BOX, [(0, 0, 2 * self.mouth, BOX[2], 0.0)], 256)
        )
        s = model.shape
        self.pin = convex_hull(
            coal_geometry(meshes.pin(s.length, s.diameter, s.tip_taper_length, s.tip_radius, 128))
        )
        self.box_tf = coal.Transform3s(np.eye(3), np.array([0.0, 0.0, -BOX[2]]))  # top at z = 0

    def _pose(self, placement: TipPlacement, s: float) -> coal.Transform3s:
        c, u = placement.local()
        rotation = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), u).matrix()
        return coal.Transform3s(rotation, c - np.array([0.0, 0.0, s]))

    def _hits(self, geometry: coal.CollisionGeometry, placement: TipPlacement, s: float) -> bool:
        result = coal.CollisionResult()
        tf = self._pose(placement, s)
        return bool(
            coal.collide(self.pin, tf, geometry, self.box_tf, coal.CollisionRequest(), result)
        )

    def drop(self, geometry: coal.CollisionGeometry, placement: TipPlacement) -> float:
        lo, hi = 0.0, 4 * CM
        assert not self._hits(geometry, placement, lo)
        if not self._hits(geometry, placement, hi):
            return math.inf
        for _ in range(32):
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if self._hits(geometry, placement, mid) else (mid, hi)
        return lo

    def classify(self, placement: TipPlacement) -> tuple[str, float | None]:
        """``mouth``, ``face`` or ``rim`` and, for the rim, the slope from Coal's normal."""
        real, face = self.drop(self.real, placement), self.drop(self.face, placement)
        if real < face - 2e-6:
            return "mouth", None
        slopes = []
        for back in (1e-6, 2e-6, 5e-6, 1e-5, 2e-5):  # just before the contact
            request, result = coal.DistanceRequest(), coal.DistanceResult()
            tf = self._pose(placement, real - back)
            coal.distance(self.pin, tf, self.real, self.box_tf, request, result)
            point = np.asarray(result.getNearestPoint2(), dtype=float)
            normal = np.asarray(result.normal, dtype=float)  # from the pin to the box
            rho = math.hypot(point[0], point[1])
            if rho > self.mouth + 5e-6:
                return "face", None
            if point[2] < -5e-6:
                return "mouth", None
            radial = np.array([point[0], point[1], 0.0]) / rho
            slopes.append(float(normal @ radial) / max(-float(normal[2]), 1e-12))
        # the median: an edge of one polygon against an edge of the other can meet at a vertex
        return "rim", float(np.median(slopes))


def decided(hole: HoleSite, model: PinModel, p: TipPlacement) -> bool:
    """Whether the decision stands within 3 µm of lateral offset and 1e-4 rad of tilt."""
    near = {
        captures(hole, model, TipPlacement(p.lateral + dl, p.axial, p.tilt + dt, p.lean), MU)
        for dl in (-3e-6, 0.0, 3e-6)
        for dt in (-1e-4, 0.0, 1e-4)
        if p.tilt + dt >= 0.0
    }
    return len(near) == 1


def compare(parts: tuple[HoleSite, PinModel], grid: list[TipPlacement]) -> dict[str, int]:
    hole, model = parts
    oracle = CoalDrop(hole, model)
    counts = {"agree": 0, "left out": 0, "mouth": 0, "face": 0, "rim": 0}
    for placement in grid:
        if not decided(hole, model, placement):
            counts["left out"] += 1
            continue
        where, slope = oracle.classify(placement)
        if slope is not None and abs(slope - MU) < 0.05:
            counts["left out"] += 1
            continue
        coal_says = where == "mouth" or (where == "rim" and slope is not None and slope > MU)
        ours = captures(hole, model, placement, MU)
        assert ours == coal_says, (placement, where, slope, entry_contact(hole, model, placement))
        counts["agree"] += 1
        counts[where] += 1
    return counts


def grid(
    lateral_cm: list[float], tilt_deg: list[float], lean_deg: list[float]
) -> list[TipPlacement]:
    return [
        TipPlacement(x * CM, HEIGHT, math.radians(t), math.radians(lean))
        for x, t, lean in itertools.product(lateral_cm, tilt_deg, lean_deg)
    ]


def test_upright_pin_is_captured_up_to_whitneys_lead(parts: tuple[HoleSite, PinModel]) -> None:
    # upright, the tip rim lands on the chamfer iff lateral + a ≤ r_m (the taper, slope
    # (b − a)/h = 0.55, is less steep than the 45° chamfer): 0.57 − 0.13 = 0.44 cm
    hole, model = parts
    for lateral, inside in ((0.0, True), (0.4399, True), (0.4401, False), (0.6, False)):
        placement = TipPlacement(lateral * CM, HEIGHT, 0.0, 0.0)
        assert captures(hole, model, placement) is inside
        contact = entry_contact(hole, model, placement)
        if inside:
            assert contact.where == "mouth"
        else:  # the flat tip face lies across the rim: it pushes straight up, no way in
            assert contact.where == "rim" and contact.slope == 0.0 and not contact.corner
    assert entry_contact(hole, model, TipPlacement(0.75 * CM, HEIGHT, 0.0, 0.0)).where == "face"
    # the drop onto the chamfer: the tip rim (r 0.13) at 0.2 cm off axis meets the cone at
    # depth r_m − 0.33 = 0.24 cm below the mouth
    contact = entry_contact(hole, model, TipPlacement(0.2 * CM, HEIGHT, 0.0, 0.0))
    assert contact.mouth == pytest.approx(HEIGHT + 0.24 * CM, abs=1e-12)
    assert contact.face == math.inf  # nothing of the upright pin is over the face


def test_capture_agrees_with_coal(parts: tuple[HoleSite, PinModel]) -> None:
    counts = compare(
        parts, grid([0.0, 0.3, 0.42, 0.46, 0.5, 0.6], [0.0, 1.0, 10.0, 30.0], [0.0, 120.0, 270.0])
    )
    assert counts["agree"] >= 60 and min(counts["mouth"], counts["face"], counts["rim"]) >= 2


@pytest.mark.slow
def test_capture_agrees_with_coal_on_the_full_grid(parts: tuple[HoleSite, PinModel]) -> None:
    lateral = [0, 0.1, 0.2, 0.3, 0.4, 0.42, 0.44, 0.46, 0.5, 0.55, 0.6, 0.65, 0.7]
    counts = compare(parts, grid(lateral, [0, 0.25, 1, 3, 10, 20, 30, 40], [0, 60, 120, 180, 270]))
    assert counts["agree"] >= 480


def test_minima_over_circles_refine_each_row_as_if_alone() -> None:
    """The eight minima of an entry contact are refined together; each row must come out as a
    refinement of that row alone would make it, bit for bit (only elementwise arithmetic and a
    per-row argmin: rows cannot mix). Functions with one, two and no finite minima on the grid.
    """
    from synth.replay.capture import _GRID, _refine

    shifts = np.array([[0.3], [2.0], [5.9], [1.0]])

    def over(rows: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
        def evaluate(phi: np.ndarray) -> np.ndarray:
            v = np.cos(phi - rows) + 0.4 * np.cos(2.0 * (phi - rows)) + rows
            v[rows[:, 0] == 1.0] = np.inf  # the row shifted by 1 is nowhere finite
            return v

        return evaluate

    grid = over(shifts)(np.broadcast_to(_GRID, (4, _GRID.size)))
    together = _refine(over(shifts), grid)
    for index in range(4):
        alone = _refine(over(shifts[index : index + 1]), grid[index : index + 1])
        assert together[0][index] == alone[0][0] and together[1][index] == alone[1][0]
    # a refined minimum lies at or below the grid's (the cosine pair's true minimum is below it)
    assert np.all(together[0][:3] <= grid[:3].min(axis=1))
    assert together[0][3] == math.inf and together[1][3] == 0.0
