"""Benchmark ``hopf``: the CPU the Hopf normal forms add to ``fempipe critical --v 0,16``.

At alpha = 0, pi/2, pi, with l1 of the first flutter; docs/cli/commands.md, "fempipe bench".
"""

from __future__ import annotations

import math
import statistics

from fempipe.analyses.stability import analyse_stability
from fempipe.analyses.stability.hopf import normal_forms
from fempipe.bench.harness import in_turns, register
from fempipe.model.discretization import DEFAULT_FE, discretization_from_name
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel


@register("hopf")
def bench_hopf(quick: bool = False) -> dict:
    """CPU-s of the normal forms of every flutter event against the stability analysis."""
    disc = discretization_from_name(DEFAULT_FE)
    alphas = (0.0,) if quick else (0.0, math.pi / 2, math.pi)
    repeats = 1 if quick else 3
    table = []
    for alpha in alphas:
        model = PipeModel(disc, Params(alpha=alpha))
        (t_an, t_nf), (_, forms) = in_turns(
            [
                lambda _, model=model: analyse_stability(model, v_max=16.0),
                lambda res, model=model: normal_forms(model, res),
            ],
            repeats,
        )
        first = min(forms.items(), key=lambda kv: kv[0][2]) if forms else None
        nf = None if first is None or isinstance(first[1], str) else first[1]
        a, h = statistics.median(t_an), statistics.median(t_nf)
        table.append(
            {
                "alpha": alpha,
                "flutter_events": len(forms),
                "analysis_cpu_s": a,
                "hopf_cpu_s": h,
                "hopf_share": h / a if a > 0 else math.nan,
                "l1_first": None if nf is None else nf.l1,
                "l1_uncertainty": None if nf is None else nf.uncertainty,
            }
        )
    return {"discretization": disc.name, "table": table}
