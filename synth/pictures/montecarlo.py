"""The Monte Carlo picture: each trial's sampled errors, coloured by its outcome.

:func:`montecarlo_picture` pairs every trial of a :class:`~synth.replay.report.ReplayReport`
with the error parameters it sampled (:func:`synth.replay.run.world_errors`, the same draw as
the trial) and the task's tolerance box; :func:`draw_montecarlo` draws the pairwise scatter of
the sampled parameters (lengths in cm, angles in degrees), one colour per outcome, the box's
bounds dashed, and every failing trial labelled ``L<line> <kind>`` (its AL line and the
violation kind or outcome), so the corner of the tolerance box that fails shows at a glance.

SVG ids (``gid``): axes ``mc-<i>-<j>`` (parameter i across, j up); in each, one marker artist
per outcome ``mc-<i>-<j>-<outcome>`` holding that outcome's trials in trial order, and the
labels ``mc-<i>-<j>-label-<trial>``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle
from numpy.typing import NDArray

from synth.models.graph import AttributeGraph
from synth.pictures.render import literal_text
from synth.replay.report import OUTCOMES, ReplayReport, RunReport

__all__ = [
    "MonteCarloPicture",
    "Parameter",
    "draw_montecarlo",
    "failure_label",
    "montecarlo_picture",
]

COLOURS = {
    "success": "tab:green",
    "failure": "tab:orange",
    "abort": "tab:red",
    "violation": "tab:purple",
    "error": "black",
}
MAX_LABELS = 20
"""Failing trials labelled one by one up to this many (beyond, the legend counts them)."""


@dataclass(frozen=True)
class Parameter:
    """One sampled error parameter: frame, name (x, y, z, rx, ry, rz), AL name, bounds [SI]."""

    frame: str
    name: str
    al_name: str
    lo: float
    hi: float

    @property
    def angle(self) -> bool:
        """True for a rotation (drawn in degrees)."""
        return self.name.startswith("r")

    @property
    def scale(self) -> float:
        """SI → drawing unit: cm for lengths, degrees for angles."""
        return 180.0 / math.pi if self.angle else 100.0

    @property
    def label(self) -> str:
        """Axis label with its unit: ``BOX x [cm]``, ``BOX rz [°]``."""
        return f"{self.al_name} {self.name} [{'°' if self.angle else 'cm'}]"


@dataclass(frozen=True, eq=False)
class MonteCarloPicture:
    """What the Monte Carlo picture shows.

    The trials' sampled ``values`` (N, P) [SI] per :class:`Parameter`, their ``outcomes`` and
    failure ``labels`` (None: the trial succeeded); ``title`` names the program and task.
    """

    title: str
    parameters: tuple[Parameter, ...]
    values: NDArray[np.float64]
    outcomes: tuple[str, ...]
    labels: tuple[str | None, ...]


def failure_label(run: RunReport) -> str | None:
    """``L<line> <kind>`` of a failing run (kind: the violation's, else the outcome); None."""
    if run.success:
        return None
    kind = run.violations[0].kind if run.violations else run.outcome
    where = f"L{run.line} " if run.line is not None else ""
    return f"{where}{kind}"


def montecarlo_picture(
    report: ReplayReport,
    errors: Sequence[Mapping[str, Mapping[str, float]]],
    graph: AttributeGraph,
) -> MonteCarloPicture:
    """The picture's data: ``errors[i]`` are trial i's sampled parameters (frame → name → value).

    The parameters drawn are those of the task's error blocks that vary (bounds not both 0),
    in task order; bounds from the graph the trials sampled.
    """
    if len(errors) != len(report.trials):
        raise ValueError(f"{len(report.trials)} trials but {len(errors)} error samples")
    parameters = []
    for frame, link in graph.links.items():
        if link.uncertainty is None:
            continue
        for name, bound in link.uncertainty.bounds().items():
            if bound.hi > bound.lo:
                al = graph.al_names[frame]
                parameters.append(Parameter(frame, name, al, bound.lo, bound.hi))
    values = np.array(
        [[float(e.get(p.frame, {}).get(p.name, 0.0)) for p in parameters] for e in errors]
    ).reshape(len(errors), len(parameters))
    return MonteCarloPicture(
        title=f"{report.program} on {report.task}: {len(report.trials)} trials",
        parameters=tuple(parameters),
        values=values,
        outcomes=tuple(r.outcome for r in report.trials),
        labels=tuple(failure_label(r) for r in report.trials),
    )


@literal_text
def draw_montecarlo(picture: MonteCarloPicture) -> Figure:
    """Pairwise scatter of the sampled errors coloured by outcome (module docstring)."""
    params = picture.parameters
    pairs = [(i, j) for j in range(len(params)) for i in range(j)]
    if not pairs:
        pairs = [(0, 0)] if params else []
    columns = min(3, max(len(pairs), 1))
    rows = max(1, math.ceil(len(pairs) / columns))
    fig = Figure(figsize=(4.2 * columns, 4.0 * rows + 0.8), layout="constrained")
    axes = fig.subplots(rows, columns, squeeze=False).ravel()
    outcomes = np.array(picture.outcomes)
    counts = {o: int(np.count_nonzero(outcomes == o)) for o in OUTCOMES}
    failing = [k for k, label in enumerate(picture.labels) if label is not None]
    for ax, (i, j) in zip(axes, pairs, strict=False):
        pi, pj = params[i], params[j]
        ax.set_gid(f"mc-{i}-{j}")
        x, y = pi.scale * picture.values[:, i], pj.scale * picture.values[:, j]
        for outcome in OUTCOMES:
            mask = outcomes == outcome
            if not mask.any():
                continue
            ax.plot(
                x[mask],
                y[mask],
                "o",
                ls="none",
                ms=3.0 if outcome == "success" else 5.0,
                color=COLOURS[outcome],
                alpha=0.6 if outcome == "success" else 0.9,
                gid=f"mc-{i}-{j}-{outcome}",
                label=f"{outcome}: {counts[outcome]}",
            )
        ax.add_patch(_box(pi.scale * pi.lo, pi.scale * pi.hi, pj.scale * pj.lo, pj.scale * pj.hi))
        if len(failing) <= MAX_LABELS:
            for k in failing:
                ax.annotate(
                    picture.labels[k],
                    (x[k], y[k]),
                    xytext=(3, 3),
                    textcoords="offset points",
                    fontsize=6,
                    color=COLOURS[picture.outcomes[k]],
                    gid=f"mc-{i}-{j}-label-{k}",
                )
        ax.set_xlabel(pi.label)
        ax.set_ylabel(pj.label)
        ax.grid(True, lw=0.3, color="0.85")
    for ax in axes[len(pairs) :]:
        ax.set_axis_off()
    if pairs:
        axes[0].legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.15), frameon=False)
    kinds: dict[str, int] = {}
    for label in picture.labels:
        if label is not None:
            kinds[label] = kinds.get(label, 0) + 1
    summary = ", ".join(f"{k} ×{n}" for k, n in sorted(kinds.items())) or "no failing trial"
    fig.suptitle(f"{picture.title}\nfailing: {summary}", fontsize=9)
    return fig


def _box(x0: float, x1: float, y0: float, y1: float) -> Rectangle:
    return Rectangle(
        (x0, y0), x1 - x0, y1 - y0, fill=False, ec="0.4", ls="--", lw=0.8, gid="tolerance-box"
    )
