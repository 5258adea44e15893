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
* ``Δθ_ok = atan(lead width / lead height)`` [rad] with lead width ``Δr_ok`` and lead height
  ``taper length + chamfer width`` (45° chamfer): the tilt at which the tip still lands on the
  combined lead. It ignores friction and compliance, which is why measured values override it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from synth.models.graph import AttributeGraph
from synth.models.spec import HoleShape, InsertionSpec, PinShape


@dataclass(frozen=True)
class InsertionParameters:
    """d_f, d_s, Δr_ok [m], Δθ_ok [rad], the direction, and where each value came from.

    ``lead`` [m] is the parts' geometric lead (the derived Δr_ok): what the replay's contact
    geometry captures, whatever Δr_ok the task gives.
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


def derive(graph: AttributeGraph, spec: InsertionSpec) -> InsertionParameters:
    """The task's insertion parameters: given values, or the rules in the module docstring."""
    pin_name, hole_name = graph.resolve(spec.pin), graph.resolve(spec.hole)
    pin_shape, hole_shape = graph.nodes[pin_name].shape, graph.nodes[hole_name].shape
    assert isinstance(pin_shape, PinShape) and isinstance(hole_shape, HoleShape)
    r_hole, r_tip = hole_shape.diameter / 2, pin_shape.tip_radius
    derived = {
        "d_f": min(hole_shape.depth, pin_shape.length - pin_shape.tip_taper_length),
        "d_s": 0.0,
        "dr_ok": hole_shape.chamfer_width + max(r_hole - r_tip, 0.0),
    }
    lead_height = pin_shape.tip_taper_length + hole_shape.chamfer_width
    values: dict[str, float] = {}
    source: dict[str, str] = {}
    for key in ("d_f", "d_s", "dr_ok"):
        given = getattr(spec, key)
        values[key] = derived[key] if given is None else given
        source[key] = "derived" if given is None else "given"
    dr_ok = values["dr_ok"]
    derived_dtheta = math.atan2(dr_ok, lead_height) if lead_height > 0 else 0.0
    values["dtheta_ok"] = derived_dtheta if spec.dtheta_ok is None else spec.dtheta_ok
    source["dtheta_ok"] = "derived" if spec.dtheta_ok is None else "given"
    start = graph.resolve(spec.start_hole) if spec.start_hole else None
    return InsertionParameters(
        pin_name, hole_name, start, spec.direction, source=source, lead=derived["dr_ok"], **values
    )
