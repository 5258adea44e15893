"""strategies stage of synth (see docs/design.md): seed ch. IV §4.1–4.6.

:func:`plan_task` turns a task into a :class:`PlanResult`: pickup strategies (§4.3), the
approach (§4.4), accuracy refinements (§4.5) and best-first selection (§4.6). The records in
:mod:`synth.strategies.records` are what code generation consumes.
"""

from synth.strategies.options import PlanOptions
from synth.strategies.planner import plan_task
from synth.strategies.records import (
    Destination,
    ErrorFootprint,
    Grasp,
    GraspStrategy,
    PinInHoleStrategy,
    PlanResult,
    Rejection,
    Search,
    Tap,
)

__all__ = [
    "Destination",
    "ErrorFootprint",
    "Grasp",
    "GraspStrategy",
    "PinInHoleStrategy",
    "PlanOptions",
    "PlanResult",
    "Rejection",
    "Search",
    "Tap",
    "plan_task",
]
