"""Time one error bound by LP (HiGHS) and by closed form, and a whole `synth errors` estimate.

Usage: python benchmarks/errors.py [--repeat N]
Prints a table of microseconds per call and the LP / closed-form ratio (same process, same
objective). The objectives are the seed's A.2 functionals Δx, Δy, Δz of hole⁻¹ ∘ tip.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from _timing import per_call_us

from synth.errors.bounds import build_error_lp, closed_form_bound, solve_error_lp
from synth.errors.chain import chain_between
from synth.errors.estimate import RelationModel, estimate_errors
from synth.models.graph import AttributeGraph
from synth.models.loader import load_task

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=200)
    args = parser.parse_args()

    graph = AttributeGraph(load_task(ROOT / "fixtures/tasks/screw_on_driver.yaml"))
    chain = chain_between(graph, "hole", "tip")
    rel = RelationModel.of(chain)
    rows = []
    for axis, name in enumerate(("Δx", "Δy", "Δz")):
        c = rel.displacement.linear[:, axis]
        lp_us = per_call_us(lambda c=c: solve_error_lp(build_error_lp(c, chain.space)), args.repeat)
        cf_us = per_call_us(lambda c=c: closed_form_bound(c, chain.space), args.repeat)
        lp = solve_error_lp(build_error_lp(c, chain.space))
        cf = closed_form_bound(c, chain.space)
        assert np.isclose(lp.hi, cf.hi) and np.isclose(lp.lo, cf.lo)
        rows.append((f"bound {name} (11 params)", lp_us, cf_us))
    full_us = per_call_us(lambda: estimate_errors(chain_between(graph, "hole", "tip")), 50)
    model_us = per_call_us(lambda: RelationModel.of(chain), args.repeat)

    print(f"{'operation':32}{'LP [µs]':>12}{'closed [µs]':>14}{'LP/closed':>12}")
    for label, lp_us, cf_us in rows:
        print(f"{label:32}{lp_us:12.1f}{cf_us:14.1f}{lp_us / cf_us:12.1f}")
    print(f"{'Taylor model of the chain':32}{'':12}{model_us:14.1f}")
    print(f"{'whole estimate (chain + bounds)':32}{'':12}{full_us:14.1f}")


if __name__ == "__main__":
    main()
