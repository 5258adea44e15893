"""The spiral search over the error footprint (seed §4.5.3 L2436, §4.8 L2740–2790).

The generated loop (L2743–2770) tries offsets on rings of radius ``R = step, 2·step, …`` with
``step = 0.75·Δr_ok`` (L2743: ``R = .572; ! 0.75*DROK``), points every ``DW = step/R`` radians
from ``W = 0`` while ``W < 2π`` (the OCR's "259°DEG" at L2755 is 2π), and keeps a point when
``|x| ≤ Δx`` and ``|y| ≤ Δy`` in the footprint frame (turned by ζ about the hole axis).

Rings: the seed's program stops at ``R ≤ 1.72 = 3·step`` for Δx = 1.58 cm (L2753), i.e.
``ceil(max(Δx, Δy)/step)`` rings; we start there and add rings (and if need be widen the filter,
:func:`search_extent`) until every point of the footprint lies within Δr_ok of a tried offset
(the first attempt at the origin included), checked on cells with each cell's half-diagonal
added so the check is conservative (:func:`coverage`).

Expected time (L2436): "we only count those points within Δx/2 and Δy/2 of the hole", each
costing one retry (``Candidate.try_time``).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from synth.strategies.options import PlanOptions
from synth.strategies.records import Search

GRID = 40
"""Cells per side of the coverage check's first grid (:func:`coverage`)."""
SPLITS = 8
"""Halvings of a coverage cell at most: cells down to 1/10 240 of the footprint's side."""
MAX_POINTS = 20_000
"""Largest search pattern planned: beyond this (Δr_ok tiny against the footprint) the planner
rejects the strategy instead of generating, checking and timing a pattern it would never run."""


def ring_points(step: float, ring: int) -> NDArray[np.float64]:
    """Offsets [m] of one ring: radius ``R = ring·step``, angles ``0, DW, 2·DW, … < 2π``."""
    radius = ring * step
    dw = step / radius
    angles = np.arange(0.0, 2 * math.pi, dw)
    return radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)


def pattern_points(step: float, rings: int) -> NDArray[np.float64]:
    """Every offset [m] of ``rings`` rings in the seed's order (origin excluded), shape (N, 2)."""
    if rings <= 0:
        return np.zeros((0, 2))
    return np.vstack([ring_points(step, k) for k in range(1, rings + 1)])


def inside(points: NDArray[np.float64], dx: float, dy: float) -> NDArray[np.bool_]:
    """Mask of the points with ``|x| ≤ dx`` and ``|y| ≤ dy`` (L2757)."""
    return (np.abs(points[:, 0]) <= dx) & (np.abs(points[:, 1]) <= dy)


def coverage(
    points: NDArray[np.float64], dx: float, dy: float, margin: float = 0.0, *, within: float
) -> float:
    """Upper bound [m] of the distance from any footprint point to the nearest tried offset.

    Tried offsets: the origin and the pattern points that pass the filter ``|x| ≤ dx + margin``,
    ``|y| ≤ dy + margin``. The distance to a point set is 1-Lipschitz, so over a cell of centre
    c and half-diagonal r it is at most d(c) + r. Start from ``GRID × GRID`` cells over the
    footprint ±dx × ±dy and split in four every cell whose bound exceeds ``within``, until every
    bound is within it, a centre itself is farther than ``within`` (the footprint is not
    covered: no split can help), or the cells are :data:`SPLITS` halvings deep. The result is
    the largest bound of the cells kept: ≤ ``within`` exactly when coverage within it is proven.

    A fixed grid's half-diagonal grows with the footprint: at 41 × 41 it is ``hypot(dx, dy)/40``,
    which for a ±5 cm footprint (±3 in hand placement) exceeds the slack between a pattern's
    true coverage (≈ 0.7·Δr_ok at step 0.75·Δr_ok) and Δr_ok, so no pattern would ever pass.
    """
    tried = np.vstack([np.zeros((1, 2)), points[inside(points, dx + margin, dy + margin)]])
    tree = cKDTree(tried)
    hx, hy = dx / GRID, dy / GRID  # [m] half-sides of the first cells
    xs = -dx + (2 * np.arange(GRID) + 1) * hx  # the first cells' centres
    ys = -dy + (2 * np.arange(GRID) + 1) * hy
    centres = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    worst = 0.0
    for depth in range(SPLITS + 1):
        d, _ = tree.query(centres)
        bound = d + math.hypot(hx, hy)
        if float(d.max()) > within or depth == SPLITS:
            return max(worst, float(bound.max()))
        loose = bound > within
        if not loose.any():
            return max(worst, float(bound.max()))
        worst = max(worst, float(bound[~loose].max(initial=0.0)))
        hx, hy = hx / 2, hy / 2
        quarters = np.array([[-hx, -hy], [hx, -hy], [-hx, hy], [hx, hy]])
        centres = (centres[loose][:, None, :] + quarters[None]).reshape(-1, 2)
    raise AssertionError("unreachable: the last depth returns")


def pattern_size(step: float, rings: int) -> int:
    """Number of points of ``rings`` rings: ``Σ_k ⌈2πk⌉ ≤ π·rings·(rings + 1) + rings``.

    O(rings): check :func:`search_size_problem` first when ``rings`` comes from the task.
    """
    return sum(math.ceil(2 * math.pi * k - 1e-9) for k in range(1, rings + 1))


def search_size_problem(dx: float, dy: float, dr_ok: float, step: float) -> str | None:
    """Why no search pattern should be planned for ±dx × ±dy [m] at ``step`` [m], or None.

    The pattern the planner would start from has ``R = seed_rings + 1`` rings, and
    ``Σ_{k≤R} ⌈2πk⌉ ≥ π·R·(R + 1)`` points; when that bound already exceeds
    :data:`MAX_POINTS` the pattern is refused in O(1), from floats, so a Δr_ok of 1e-9 cm
    (10⁹ rings) is never enumerated or even summed. Below the bound (R ≤ 80) the size is
    counted exactly. A step that is not positive and finite (Δr_ok = 0) is refused too. The
    wording ("error footprint …, search of about N points") is the ``footprint`` cause of
    :mod:`synth.strategies.causes`.
    """
    where = f"error footprint ±{100 * dx:.3g} cm × ±{100 * dy:.3g} cm against Δr_ok = "
    where += f"{100 * dr_ok:.3g} cm"
    if not (math.isfinite(step) and step > 0.0):
        return f"{where} needs a search of about infinitely many points (no spacing)"
    rings_f = max(dx, dy) / step + 1.0  # [1] seed_rings + 1, as a float: it may be huge
    lower = math.pi * rings_f * (rings_f + 1.0)
    if lower > MAX_POINTS:
        return f"{where} needs a search of about {lower:.3g} points (more than {MAX_POINTS})"
    size = pattern_size(step, seed_rings(dx, dy, step) + 1)
    if size > MAX_POINTS:
        return f"{where} needs a search of about {size} points (more than {MAX_POINTS})"
    return None


def seed_rings(dx: float, dy: float, step: float) -> int:
    """The seed's ring count ``ceil(max(Δx, Δy)/step)`` (L2753), at least 1."""
    return max(1, math.ceil(max(dx, dy) / step - 1e-12))


def search_extent(dx: float, dy: float, dr_ok: float, step: float) -> tuple[int, float]:
    """``(rings, margin)``: pattern size [1] and widening of the point filter [m].

    Start with the seed's ``ceil(max(Δx, Δy)/step)`` rings and the filter ``|x| ≤ Δx``,
    ``|y| ≤ Δy``; add rings (up to the footprint's corner) until every footprint point lies
    within Δr_ok of a tried offset. Near the footprint's edges the filter can drop the only
    ring points that would cover them (a 2.2 × 2.2 cm footprint is never covered by the seed's
    filter); then widen the filter by step/4, step/2, … and try again.
    """
    first = seed_rings(dx, dy, step)
    for quarter in range(0, 9):
        margin = quarter * step / 4
        last = max(first, math.ceil((math.hypot(dx, dy) + margin) / step)) + 1
        for rings in range(first, last + 1):
            points = pattern_points(step, rings)
            if coverage(points, dx, dy, margin, within=dr_ok) <= dr_ok:
                return rings, margin
    raise ValueError(f"no search pattern of step {step} m covers {dx} × {dy} m within {dr_ok} m")


def tried_points(search: Search) -> int:
    """Pattern points the program tries: every one that passes its filter ``|x| ≤ dx, |y| ≤ dy``."""
    return int(
        np.count_nonzero(inside(pattern_points(search.step, search.rings), search.dx, search.dy))
    )


def search_time_problem(
    search: Search, try_time: float, other_time: float, max_time: float
) -> str | None:
    """Why a search is too long for its program to be replayed, or None.

    The L2436 estimate counts the points within Δx/2, Δy/2; a trial whose pin lies at the
    footprint's corner tries nearly every point, ``(tried_points + 1)·try_time`` [s] (the first
    attempt included) on top of ``other_time`` [s] (pickup, transport, tap). The referee ends a
    run past ``max_time`` [s] of simulated time (:data:`synth.al.interpreter.MAX_TIME`, its
    guard against endless loops), so such a program could never be proven: refuse it here, with
    the ``footprint`` wording of :mod:`synth.strategies.causes`.
    """
    points = tried_points(search)
    worst = (points + 1) * try_time + other_time
    if worst <= max_time:
        return None
    return (
        f"error footprint ±{100 * search.dx:.3g} cm × ±{100 * search.dy:.3g} cm: its search of "
        f"{points} points may take {worst:.0f} s with the rest of the program, more than the "
        f"{max_time:g} s of simulated time a replayed run may take"
    )


def expected_points(points: NDArray[np.float64], dx: float, dy: float) -> int:
    """Pattern points within ``Δx/2, Δy/2`` of the hole (L2436)."""
    return int(np.count_nonzero(inside(points, dx / 2, dy / 2)))


def points_within_box(step: float, half_x: float, half_y: float) -> int:
    """Pattern points with ``|x| ≤ half_x``, ``|y| ≤ half_y`` [m] (rings out to the corner)."""
    if not (math.isfinite(step) and step > 0.0):
        return 0  # no pattern at all: refused later (search_size_problem); 0 stays admissible
    rings_f = math.hypot(half_x, half_y) / step
    if math.pi * rings_f * (rings_f - 1.0) > MAX_POINTS:  # ≤ pattern_size(floor(rings_f))
        return 0  # a pattern this large is rejected anyway; 0 keeps the bound admissible
    rings = math.floor(rings_f + 1e-12)
    if pattern_size(step, rings) > MAX_POINTS:
        return 0  # a pattern this large is rejected anyway; 0 keeps the bound admissible
    return expected_points(pattern_points(step, rings), 2 * half_x, 2 * half_y)


def plan_search(
    dx: float, dy: float, zeta: float, dr_ok: float, try_time: float, options: PlanOptions
) -> Search:
    """The search record for a footprint ±dx × ±dy turned by ζ [m, rad], retry time [s].

    The record's ``dx``, ``dy`` are the program's point filter: the footprint, widened by the
    margin of :func:`search_extent` when the seed's filter would leave a gap (none for the
    seed's fixtures). The expected count uses the footprint itself (L2436).
    """
    step = options.search_step_fraction * dr_ok
    rings, margin = search_extent(dx, dy, dr_ok, step)
    count = expected_points(pattern_points(step, rings), dx, dy)
    return Search(
        dx=dx + margin,
        dy=dy + margin,
        zeta=zeta,
        step=step,
        rings=rings,
        expected_points=count,
        time=count * try_time,
        off_surface=options.search_off_surface,
    )
