"""Insertion parameters of seed §4.2 (L1990–2010), derived from the pin and hole geometry.

The seed measured d_f, d_s, Δr_ok and Δθ_ok on the real parts because computing them "turned
out to be extremely tedious, and ignored some important factors, such as friction" (L2005). A
task may still give them (they override); otherwise these documented rules apply:

* ``d_f = min(hole depth, pin length − tip taper)`` [m]: the pin goes in until it bottoms out;
* ``d_s = 0`` [m]: a pin that misses lands on the surface instead of jamming part-way (the
  seed's own value for its pin, L2583);
* ``Δr_ok = w_chamfer + (r_hole − r_tip)`` [m]: Whitney's lead condition — the lateral error a
  chamfered peg-hole pair absorbs is the hole chamfer width plus the peg's chamfer
  (``r_shaft − r_tip``) plus the radial clearance (``r_hole − r_shaft``);
* ``Δθ_ok = min(atan(lead width / lead height), θ_wedge)`` [rad]: the tilt at which the entering
  end still lands on the combined lead (lead width ``Δr_ok``, lead height ``taper length +
  chamfer width``, 45° chamfer), and at most Whitney's wedging limit ``θ_wedge = c/μ`` with
  clearance ratio ``c = (D − d)/D`` and friction μ (:mod:`synth.models.jamming`). A tilt
  above θ_wedge at entry can wedge the pin at its two-point contact whatever the chamfers.

A given d_f, d_s or Δr_ok overrides its rule. A given Δθ_ok is kept up to θ_wedge and clipped
to it above (``source`` says so, ``notes`` explains): the replay wedges such a pin.

The entering end is the tip for a ``parallel`` insertion and the head (the shaft's full
radius, no taper) for an ``antiparallel`` one. The planner refuses antiparallel insertions
(:func:`refuse_unprovable`): no program for them can be proven yet.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal, Protocol

from synth.exceptions import SpecError
from synth.models.graph import AttributeGraph
from synth.models.jamming import wedging_tilt
from synth.models.spec import HoleShape, InsertionSpec, PinShape


@dataclass(frozen=True)
class InsertionParameters:
    """d_f, d_s, Δr_ok [m], Δθ_ok [rad], the direction, and where each value came from.

    ``lead`` [m] is the parts' geometric lead (the derived Δr_ok), whatever Δr_ok the task
    gives: for an upright pin it is what the replay captures, which the replay decides from the
    parts themselves (:mod:`synth.replay.capture`), never from these formulas. ``friction``
    [1] is μ and ``wedge_tilt`` [rad] Whitney's θ_wedge = c/μ, the bound on ``dtheta_ok``;
    ``notes`` are remarks for the plan (a given value clipped). ``lead_height`` [m] is the
    entering end's taper plus the chamfer's width, over which the lead is taken up. ``seat``
    [m] is the derived d_f, the depth at which the pin bottoms out, whatever d_f the task
    gives; ``seat_by`` names what stops it (``the hole's depth`` or ``the pin's length less
    its tip taper``).
    """

    pin: str
    hole: str
    start_hole: str | None
    direction: Literal["parallel", "antiparallel"]
    d_f: float
    d_s: float
    dr_ok: float
    dtheta_ok: float
    source: dict[str, str]
    lead: float
    friction: float
    wedge_tilt: float
    seat: float
    seat_by: str
    notes: tuple[str, ...] = ()
    lead_height: float = 0.0


def derived_d_f(pin_shape: PinShape, hole_shape: HoleShape) -> float:
    """d_f [m] when the task gives none: ``min(hole depth, pin length − tip taper)``."""
    return min(hole_shape.depth, pin_shape.length - pin_shape.tip_taper_length)


def derive(graph: AttributeGraph, spec: InsertionSpec) -> InsertionParameters:
    """The task's insertion parameters: given values, or the rules in the module docstring."""
    pin_name, hole_name = graph.resolve(spec.pin), graph.resolve(spec.hole)
    pin_shape, hole_shape = graph.nodes[pin_name].shape, graph.nodes[hole_name].shape
    assert isinstance(pin_shape, PinShape) and isinstance(hole_shape, HoleShape)
    r_hole = hole_shape.diameter / 2
    # the entering end: the tapered tip, or the flat head of a turned-over pin
    head_first = spec.direction == "antiparallel"
    r_end = pin_shape.diameter / 2 if head_first else pin_shape.tip_radius
    taper = 0.0 if head_first else pin_shape.tip_taper_length
    reach = pin_shape.length - pin_shape.tip_taper_length
    derived = {
        "d_f": derived_d_f(pin_shape, hole_shape),
        "d_s": 0.0,
        "dr_ok": hole_shape.chamfer_width + max(r_hole - r_end, 0.0),
    }
    lead_height = taper + hole_shape.chamfer_width
    values: dict[str, float] = {}
    source: dict[str, str] = {}
    for key in ("d_f", "d_s", "dr_ok"):
        given = getattr(spec, key)
        values[key] = derived[key] if given is None else given
        source[key] = "derived" if given is None else "given"
    dr_ok = values["dr_ok"]
    friction = spec.friction
    wedge = wedging_tilt(hole_shape.diameter, pin_shape.diameter, friction)
    lead_tilt = math.atan2(dr_ok, lead_height) if lead_height > 0 else math.pi / 2
    notes: list[str] = []
    if spec.dtheta_ok is None:
        values["dtheta_ok"] = min(lead_tilt, wedge)
        source["dtheta_ok"] = "derived" if lead_tilt <= wedge else "derived: wedging limit"
    elif spec.dtheta_ok > wedge:
        values["dtheta_ok"] = wedge
        source["dtheta_ok"] = "given, clipped to the wedging limit"
        notes.append(
            f"note: the task's Δθ_ok = {math.degrees(spec.dtheta_ok):.3f}° exceeds the wedging "
            f"limit c/μ = {math.degrees(wedge):.3f}° (clearance ratio "
            f"{(hole_shape.diameter - pin_shape.diameter) / hole_shape.diameter:.4f}, "
            f"μ = {friction:g}; Whitney 1982); planned with the limit"
        )
    else:
        values["dtheta_ok"] = spec.dtheta_ok
        source["dtheta_ok"] = "given"
    start = graph.resolve(spec.start_hole) if spec.start_hole else None
    return InsertionParameters(
        pin_name,
        hole_name,
        start,
        spec.direction,
        source=source,
        lead=derived["dr_ok"],
        friction=friction,
        wedge_tilt=wedge,
        seat=derived["d_f"],
        seat_by=(
            "the hole's depth"
            if hole_shape.depth <= reach
            else "the pin's length less its tip taper"
        ),
        notes=tuple(notes),
        lead_height=lead_height,
        **values,
    )


class Led(Protocol):
    """What was planned with a Δr_ok and the parts' lead: parameters, or a strategy."""

    @property
    def dr_ok(self) -> float:
        """[m] the lateral error the search is spaced by."""

    @property
    def lead(self) -> float | None:
        """[m] chamfer + hole radius − tip radius (None: not derived)."""


def exceeds_lead(planned: Led) -> bool:
    """Whether the Δr_ok planned with is wider than the parts' geometric lead (None: unknown)."""
    return planned.lead is not None and planned.dr_ok > planned.lead + 1e-9


def at_lead(params: InsertionParameters, why: str) -> InsertionParameters:
    """The parameters with Δr_ok the parts' geometric lead, and Δθ_ok the lead's tilt at most.

    Δr_ok and Δθ_ok given by the task (measured, seed L1963) include the accommodation of the
    seed's real arm; the replay captures from the parts' geometry alone (Whitney's lead
    condition, :mod:`synth.replay.capture`): lateral error up to ``lead``, tilt up to
    ``atan(lead / lead_height)``. ``why`` is the note the plan carries.
    """
    lead_tilt = (
        math.atan2(params.lead, params.lead_height) if params.lead_height > 0 else math.pi / 2
    )
    dtheta_ok = min(params.dtheta_ok, lead_tilt)
    source = dict(params.source, dr_ok="the geometric lead")
    if dtheta_ok < params.dtheta_ok:
        source["dtheta_ok"] = "the geometric lead's tilt"
    return dataclasses.replace(
        params,
        dr_ok=params.lead,
        dtheta_ok=dtheta_ok,
        source=source,
        notes=(*params.notes, why),
    )


def refuse_unprovable(
    params: InsertionParameters,
    pin_al: str,
    hole_al: str,
    reading_floor: float,
    line_of: Callable[[str], int | None],
) -> None:
    """Raise :class:`SpecError` for a task no program can be proven on.

    ``line_of`` gives a field's YAML line, for the error.

    At ``insertion.d_f``, a given d_f shallower than where the pin bottoms out (``seat``) by
    more than ``reading_floor`` [m], the least margin the success test keeps over a seated
    pin's reading (:func:`~synth.strategies.refine.success_threshold`): the replay pushes the
    pin to the bottom, where it reads ``seat − d_f`` deeper than the program expects, and a
    pin that missed reads ``d_f − d_s`` off; the test takes the seated pin for a miss once the
    first exceeds the margin, so every candidate's nominal run aborts.

    At ``insertion.direction``, a turned-over (antiparallel) pin: the replay captures, seats and
    checks a pin by its tapered tip only, never by its head; and the emitted guard
    ``FORCE(ORIENT(pin)*ZHAT)`` is evaluated when its motion starts (AL evaluates a motion's
    expressions then, like its destinations), so in every search move, which starts with the
    pin already turned over, it points into the hole and never feels the pin arrive.
    """
    short = params.seat - params.d_f
    if params.source["d_f"] == "given" and short > reading_floor:
        raise SpecError(
            "insertion.d_f",
            f"d_f = {100 * params.d_f:.4g} cm is shallower than where {pin_al} seats in "
            f"{hole_al}: {100 * params.seat:.4g} cm, {params.seat_by} (the pin goes in until it "
            f"bottoms out); a seated pin would read {100 * short:.4g} cm off the program's "
            f"success test, which allows {100 * reading_floor:.4g} cm above the depth error; "
            f"give d_f = {100 * params.seat:.4g} cm or leave it out",
            line_of("insertion.d_f"),
        )
    if params.direction != "antiparallel":
        return
    raise SpecError(
        "insertion.direction",
        f"a turned-over pin cannot be planned yet: {pin_al} would enter {hole_al} head first, "
        "and the replay captures and seats a pin only by its tip while the search's force "
        f"guard FORCE(ORIENT({pin_al})*ZHAT) would point into the hole, so no program could "
        "be proven; insert it tip first (direction: parallel)",
        line_of("insertion.direction"),
    )
