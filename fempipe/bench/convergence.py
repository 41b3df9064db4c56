"""The convergence benchmark ``convergence_vcr`` (registered with :mod:`fempipe.bench`)."""

from __future__ import annotations

import time
from dataclasses import replace

from fempipe.bench.harness import PAPER, best_time, register
from fempipe.model.params import Params
from fempipe.studies.convergence import Family, Quantity, doubling, run_study


@register("convergence_vcr")
def bench_convergence_vcr(quick: bool = False) -> dict:
    """CPU seconds and observed orders of ``fempipe convergence --quantity v_cr_in_plane --alpha pi/2
    --v 0,10 --fe P1,P2,P3 --modal 2:32 --basis sine,beam`` in this process (quick: 2:8)."""
    elements = doubling(2, 8 if quick else 64)
    modes = doubling(2, 8 if quick else 32)
    families = [Family("fe", tuple(elements), degree=k) for k in (1, 2, 3)] + [
        Family("modal", tuple(modes), basis=b) for b in ("sine", "beam")
    ]
    q = Quantity("v_cr_in_plane", replace(Params(**PAPER), v=0.0), v_max=10.0)
    cpu, study = best_time(lambda: run_study(q, families), clock=time.process_time)
    return {
        "v_cr_reference": float(study.reference.value),
        "reference_error_estimate": study.reference.error_estimate,
        "cpu_seconds": cpu,
        "table": [
            {
                "family": s.family,
                "n": f"{int(s.n[0])}..{int(s.n[-1])}",
                "cpu_seconds": round(s.cpu_time, 2),
                "observed_order": round(s.observed_order, 3),
                "expected_order": s.expected_order,
                "finest_error": float(s.errors[-1]),
            }
            for s in study.series
        ],
    }
