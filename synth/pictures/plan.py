"""The plan picture: a top view in the hole's frame and a side view with the heights.

:func:`plan_picture` gathers every number from the planner's records (a
:class:`~synth.strategies.records.PinInHoleStrategy` and the believed graph it was planned in)
into a :class:`PlanPicture`, in the hole's frame [m]; :func:`draw_plan` draws it. Nothing is
decided here: the search points are the program's (seed §4.8, L2743–2770: rings of radius
``k·step``, points every ``step/R`` rad, kept when ``|x| ≤ Δx``, ``|y| ≤ Δy``, turned by ζ), in
the order the program tries them, after the first attempt at the hole's centre.

Every artist carries a matplotlib ``gid`` (the SVG element id) so that tests and tools can find
it: ``outline``, ``hole-<AL>``, ``footprint-certified``, ``footprint-first-order``,
``search-ring-<k>``, ``search-points``, ``tap-place``, ``tap-ring``, ``approach-phi`` in the top
view (axes ``top-view``, in cm); ``height-<name>`` lines in the side view (axes ``side-view``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Circle, FancyArrowPatch, Polygon, Rectangle
from numpy.typing import NDArray

from synth.models.graph import AttributeGraph
from synth.models.spec import HoleShape, PinShape
from synth.pictures.render import literal_text
from synth.strategies.records import ErrorFootprint, PinInHoleStrategy
from synth.strategies.search import inside, pattern_points
from synth.strategies.tapping import surface_region
from synth.units import CM

__all__ = ["Height", "PlanPicture", "draw_plan", "footprint_corners", "plan_picture"]

TO_CM = 1.0 / CM
"""Drawing unit: centimetres per metre."""


@dataclass(frozen=True)
class Height:
    """A height along the hole's axis [m] (z = 0 on the surface, up out of the hole)."""

    name: str
    label: str
    z: float


@dataclass(frozen=True, eq=False)
class PlanPicture:
    """What the plan picture shows, in the hole's frame [m, rad].

    ``outline`` (N, 2) is the surface the hole is in; ``holes`` every hole mouth in it as
    ``(AL name, x, y, bore radius)``; ``footprint`` the certified pin-tip error box and
    ``first_order`` the seed's linearised one as ``(Δx, Δy, ζ)``; ``search_points`` (M, 2) the
    offsets the program tries, in order, the first attempt (0, 0) first (empty without a
    search); ``ring_radii`` the search rings; ``tap`` the tapping place ``(x, y)`` and
    ``tap_ring`` the ring of candidate places it came from (M, 2); ``phi`` the pin's rotation
    about the hole axis at insertion; ``dz`` the certified height error along the axis and
    ``dz_after_tap`` the same once the tap has measured it (None: no tap); ``heights`` the side
    view's levels.
    """

    task: str
    strategy: str
    hole: str
    outline: NDArray[np.float64]
    holes: tuple[tuple[str, float, float, float], ...]
    footprint: tuple[float, float, float]
    first_order: tuple[float, float, float] | None
    search_points: NDArray[np.float64]
    ring_radii: tuple[float, ...]
    tap: tuple[float, float] | None
    tap_ring: NDArray[np.float64]
    phi: float
    dz: float
    dz_after_tap: float | None
    hole_radius: float
    hole_depth: float
    pin_radius: float
    heights: tuple[Height, ...]
    decisions: tuple[str, ...]
    step: str = ""
    """Which step of a sequence the picture draws (``step 1 of 2 (PIN1 into PH1)``), or ""."""


def footprint_corners(dx: float, dy: float, zeta: float) -> NDArray[np.float64]:
    """Corners (4, 2) [m] of the box ±dx × ±dy turned by ζ about the hole axis."""
    c, s = math.cos(zeta), math.sin(zeta)
    box = np.array([[dx, dy], [-dx, dy], [-dx, -dy], [dx, -dy]])
    return box @ np.array([[c, s], [-s, c]])


def _search_points(strategy: PinInHoleStrategy) -> tuple[NDArray[np.float64], tuple[float, ...]]:
    search = strategy.search
    if search is None:
        return np.zeros((0, 2)), ()
    points = pattern_points(search.step, search.rings)
    kept = points[inside(points, search.dx, search.dy)]
    c, s = math.cos(search.zeta), math.sin(search.zeta)
    turned = kept @ np.array([[c, s], [-s, c]])  # ROT(ZHAT, ζ)*VECTOR(X, Y, 0), L2760
    radii = tuple(k * search.step for k in range(1, search.rings + 1))
    return np.vstack([np.zeros((1, 2)), turned]), radii


def _heights(strategy: PinInHoleStrategy, graph: AttributeGraph) -> tuple[Height, ...]:
    # The pin end's frame in the pin frame, from the approach point's definition (L2146):
    # PIN1 = BH1*xf with xf = trans(rot(ẑ, φ), (0, 0, standoff)) ∘ T_pin_end⁻¹.
    at_approach = pin.SE3(
        pin.exp3(np.array([0.0, 0.0, strategy.phi])), np.array([0.0, 0.0, strategy.standoff])
    )
    pin_from_end = strategy.approach.xf.inverse() * at_approach
    heights = [
        Height("surface", "surface", 0.0),
        Height("approach", "approach point (standoff)", strategy.standoff),
        Height("seat", "seat (d_f)", -strategy.d_f),
        Height("dtry", "guarded-move target (dtry)", -strategy.dtry),
    ]
    for k, via in enumerate(strategy.approach_vias, start=1):
        z = float((via.xf * pin_from_end).translation[2])
        heights.append(Height(f"via-{k}", f"approach via {k}", z))
    if strategy.tap is not None:
        z = float((strategy.tap.via.xf * pin_from_end).translation[2])
        heights.append(Height("tap-via", "tap start", z))
    return tuple(heights)


def plan_picture(strategy: PinInHoleStrategy, graph: AttributeGraph, step: str = "") -> PlanPicture:
    """The picture's data from a refined strategy and the graph it was planned in.

    ``step``: which step of a sequence the strategy is (the title says so), or "".
    """
    errors: ErrorFootprint | None = strategy.errors
    if errors is None:
        raise ValueError(f"strategy {strategy.name} is not refined: it has no error footprint")
    hole_frame = graph.resolve(strategy.hole)
    hole_shape = graph.node(hole_frame).shape
    assert isinstance(hole_shape, HoleShape)
    surface = graph.resolve(hole_shape.surface)
    region = surface_region(graph, surface)
    hole_from_surface = graph.relative(hole_frame, surface)

    def to_hole(points: NDArray[np.float64]) -> NDArray[np.float64]:
        xyz = np.column_stack([points, np.zeros(len(points))])
        return np.array([hole_from_surface.act(p)[:2] for p in xyz]).reshape(-1, 2)

    outline = to_hole(np.asarray(region.outline.exterior.coords, dtype=float)[:-1])
    holes = []
    for node in graph.holes_in(surface):
        shape = node.shape
        assert isinstance(shape, HoleShape)
        centre = graph.relative(hole_frame, node.name).translation
        holes.append((node.al_name, float(centre[0]), float(centre[1]), shape.diameter / 2))
    first = errors.first_order
    first_order = (first["dx"], first["dy"], first["zeta"]) if "dx" in first else None
    points, radii = _search_points(strategy)
    tap = strategy.tap
    tap_ring = np.zeros((0, 2))
    if tap is not None and tap.ring:
        tap_ring = to_hole(np.array([(x, y) for x, y, _ in tap.ring]))
    pin_shape = graph.node(strategy.pin).shape
    assert isinstance(pin_shape, PinShape)
    return PlanPicture(
        task=graph.spec.name,
        strategy=strategy.name,
        hole=graph.al_names[hole_frame],
        outline=outline,
        holes=tuple(holes),
        footprint=(errors.dx, errors.dy, errors.zeta),
        first_order=first_order,
        search_points=points,
        ring_radii=radii,
        tap=None if tap is None else (tap.offset[0], tap.offset[1]),
        tap_ring=tap_ring,
        phi=strategy.phi,
        dz=errors.dz,
        dz_after_tap=None if tap is None else tap.dz_after,
        hole_radius=hole_shape.diameter / 2,
        hole_depth=hole_shape.depth,
        pin_radius=pin_shape.diameter / 2,
        heights=_heights(strategy, graph),
        decisions=strategy.decisions,
        step=step,
    )


def _cm(value: float) -> str:
    return f"{TO_CM * value:.3g} cm"


def _top_view(ax: Axes, p: PlanPicture) -> None:
    ax.set_gid("top-view")
    ax.add_patch(
        Polygon(
            TO_CM * p.outline, closed=True, fill=True, fc="0.93", ec="0.3", lw=1.0, gid="outline"
        )
    )
    ax.plot([], [], color="0.3", lw=1.0, label="surface outline")
    for name, x, y, r in p.holes:
        target = name == p.hole
        ax.add_patch(
            Circle(
                (TO_CM * x, TO_CM * y),
                TO_CM * r,
                fc="white",
                ec="black" if target else "0.4",
                lw=1.4 if target else 0.8,
                gid=f"hole-{name}",
            )
        )
        ax.annotate(
            name,
            (TO_CM * x, TO_CM * y),
            xytext=(0, 9),
            textcoords="offset points",
            ha="center",
            fontsize=7,
        )
    dx, dy, zeta = p.footprint
    ax.add_patch(
        Polygon(
            TO_CM * footprint_corners(dx, dy, zeta),
            closed=True,
            fill=False,
            ec="tab:red",
            lw=1.4,
            gid="footprint-certified",
            label=f"certified footprint ±{_cm(dx)} × ±{_cm(dy)}, ζ = {math.degrees(zeta):.0f}°",
        )
    )
    if p.first_order is not None:
        fx, fy, fzeta = p.first_order
        ax.add_patch(
            Polygon(
                TO_CM * footprint_corners(fx, fy, fzeta),
                closed=True,
                fill=False,
                ec="tab:orange",
                lw=1.0,
                ls="--",
                gid="footprint-first-order",
                label=f"first-order footprint ±{_cm(fx)} × ±{_cm(fy)}, "
                f"ζ = {math.degrees(fzeta):.0f}°",
            )
        )
    for k, radius in enumerate(p.ring_radii, start=1):
        ax.add_patch(
            Circle(
                (0, 0),
                TO_CM * radius,
                fill=False,
                ec="tab:blue",
                lw=0.5,
                ls=":",
                gid=f"search-ring-{k}",
            )
        )
    if len(p.search_points):
        pts = TO_CM * p.search_points
        step = TO_CM * p.ring_radii[0]
        ax.plot(
            pts[:, 0],
            pts[:, 1],
            "-o",
            color="tab:blue",
            lw=0.6,
            ms=3.5,
            gid="search-points",
            label=f"search: {len(pts) - 1} points on {len(p.ring_radii)} rings "
            f"{step:.3g} cm apart, in order",
        )
        for k, (x, y) in enumerate(pts):
            ax.annotate(
                str(k),
                (x, y),
                xytext=(2, 2),
                textcoords="offset points",
                fontsize=5,
                color="tab:blue",
            )
    if len(p.tap_ring):
        ring = TO_CM * p.tap_ring
        ax.plot(
            ring[:, 0],
            ring[:, 1],
            ".",
            color="tab:green",
            ms=2,
            gid="tap-ring",
            label="candidate tapping places",
        )
    if p.tap is not None:
        tx, ty = p.tap
        ax.plot(
            [TO_CM * tx],
            [TO_CM * ty],
            "*",
            color="tab:green",
            ms=12,
            mec="black",
            mew=0.5,
            gid="tap-place",
            label=f"tapping place ({_cm(tx)}, {_cm(ty)})",
        )
    extent = float(np.max(np.abs(TO_CM * p.outline))) if len(p.outline) else 2.0
    length = 0.35 * extent
    ax.add_patch(
        FancyArrowPatch(
            (0, 0),
            (length * math.cos(p.phi), length * math.sin(p.phi)),
            arrowstyle="-|>",
            mutation_scale=10,
            color="tab:purple",
            lw=1.2,
            gid="approach-phi",
        )
    )
    ax.plot([], [], color="tab:purple", label=f"pin x at insertion, φ = {math.degrees(p.phi):.0f}°")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel(f"x in {p.hole} [cm]")
    ax.set_ylabel(f"y in {p.hole} [cm]")
    ax.set_title(f"top view in {p.hole}'s frame", fontsize=9)
    ax.grid(True, lw=0.3, color="0.85")
    ax.legend(fontsize=6, loc="upper left", bbox_to_anchor=(0.0, -0.12), frameon=False)


def _side_view(ax: Axes, p: PlanPicture) -> None:
    ax.set_gid("side-view")
    r, depth = TO_CM * p.hole_radius, TO_CM * p.hole_depth
    width = max(4 * r, 2.0)
    bottom = min(TO_CM * h.z for h in p.heights) - 0.5
    ax.add_patch(
        Polygon(
            [
                (-width, 0),
                (-r, 0),
                (-r, -depth),
                (r, -depth),
                (r, 0),
                (width, 0),
                (width, bottom),
                (-width, bottom),
            ],
            closed=True,
            fc="0.9",
            ec="0.3",
            lw=0.8,
            gid="hole-section",
        )
    )
    before = " before the tap" if p.dz_after_tap is not None else ""
    ax.axhspan(
        -TO_CM * p.dz,
        TO_CM * p.dz,
        color="tab:red",
        alpha=0.12,
        lw=0,
        gid="dz-band",
        label=f"surface height error{before} ±{_cm(p.dz)} (Δz)",
    )
    if p.dz_after_tap is not None:
        after = TO_CM * p.dz_after_tap
        ax.axhspan(
            -after,
            after,
            color="tab:red",
            alpha=0.35,
            lw=0,
            gid="dz-band-after-tap",
            label=f"after the tap ±{_cm(p.dz_after_tap)}",
        )
    approach = next(h for h in p.heights if h.name == "approach")
    pin_r = TO_CM * p.pin_radius
    ax.add_patch(
        Rectangle(
            (-pin_r, TO_CM * approach.z),
            2 * pin_r,
            1.5 * width,
            fc="tab:blue",
            alpha=0.25,
            ec="tab:blue",
            lw=0.6,
            gid="pin-at-approach",
        )
    )
    colours = {"surface": "0.2", "approach": "tab:blue", "seat": "tab:green", "dtry": "tab:red"}
    for k, h in enumerate(p.heights):
        z = TO_CM * h.z
        ax.axhline(
            z,
            color=colours.get(h.name, "tab:gray"),
            lw=0.8,
            ls="-" if h.name in colours else "--",
            gid=f"height-{h.name}",
        )
        ax.annotate(
            f"{h.label}: z = {z:+.3g} cm",
            (1.0, z),
            xycoords=("axes fraction", "data"),
            xytext=(4, 0 if k % 2 == 0 else -6),
            textcoords="offset points",
            fontsize=6,
            va="center",
        )
    ax.set_xlim(-width, width)
    ax.set_ylim(bottom, max(TO_CM * h.z for h in p.heights) + 0.8)
    ax.set_xlabel(f"x in {p.hole} [cm]")
    ax.set_ylabel(f"z along {p.hole}'s axis [cm]")
    ax.set_title("side view: heights along the hole axis", fontsize=9)
    ax.legend(fontsize=6, loc="upper left", bbox_to_anchor=(0.0, -0.12), frameon=False)


@literal_text
def draw_plan(picture: PlanPicture) -> Figure:
    """The plan figure: top view (left) and side view (right); see the module docstring."""
    fig = Figure(figsize=(11.0, 6.2), layout="constrained")
    top, side = fig.subplots(1, 2, width_ratios=(1.4, 1.0))
    _top_view(top, picture)
    _side_view(side, picture)
    step = f", {picture.step}" if picture.step else ""
    fig.suptitle(f"{picture.task}{step}: plan {picture.strategy}", fontsize=10)
    return fig
