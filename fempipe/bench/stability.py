"""Benchmark ``critical_vs_classical``: ``fempipe critical`` against a classical beam-mode Galerkin.

CPU seconds of fresh processes and v_cr errors; docs/cli/commands.md, "fempipe bench".
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from fempipe.analyses.stability import PLANES, find_critical_velocity
from fempipe.bench.harness import child_json, register
from fempipe.core import parallel
from fempipe.model.discretization import discretization_from_name
from fempipe.model.params import PAPER_CASE, Params
from fempipe.model.plane.operators import PipeModel
from fempipe.validation.classical import StraightPipe
from fempipe.validation.classical import critical_velocity as classical_critical_velocity

#: The reference case: the hanging pipe of the classical theory.
REFERENCE_ARGS = ["--alpha", "0", "--beta", "0.2", "--gamma", "10", "--mu", "0", "--v", "0,10"]
#: The paper's case at alpha = pi/2 (beta, gamma, mu are the CLI's defaults).
CURVED_ARGS = ["--alpha", "pi/2", "--v", "0,10"]
#: The baseline script, run by its path (it imports nothing of fempipe).
BASELINE = Path(__file__).resolve().parents[1] / "validation" / "classical_baseline.py"
#: fempipe's CPU seconds over the 40-mode baseline's must not exceed this.
TARGET_RATIO = 1.0


def _blas_env(one_thread: bool) -> dict:
    """The baseline's environment: one BLAS thread, or as written (unset what fempipe's command line set)."""
    if one_thread:
        return dict.fromkeys(parallel.BLAS_THREAD_VARIABLES, "1")
    return dict.fromkeys(parallel.BLAS_SET_BY_FEMPIPE)


def _rows(commands: list[tuple], runs: int) -> tuple[list[dict], list]:
    """Per command: median CPU seconds of ``runs`` fresh processes in turns, its v_cr error, CPU by round."""
    for _, argv, _, env in commands:
        child_json(argv, env)
    times: list[list[float]] = [[] for _ in commands]
    outs: list = [None] * len(commands)
    for _ in range(runs):
        for i, (_, argv, _, env) in enumerate(commands):
            cpu, outs[i] = child_json(argv, env)
            times[i].append(cpu)
    rows = []
    for (label, _, reference, _), t, out in zip(commands, times, outs, strict=True):
        v_cr = out["v_cr"]
        err = None if v_cr is None else abs(v_cr - reference)
        rows.append(
            {
                "command": label,
                "cpu_seconds": round(float(np.median(t)), 3),
                "min": round(min(t), 3),
                "v_cr": None if v_cr is None else f"{v_cr:.10f}",
                "abs_error": err,
                "rel_error": None if err is None else err / abs(reference),
            }
        )
    return rows, times


def _classical_reference() -> float:
    """v_cr of the hanging pipe (beta 0.2, gamma 10, mu 0): Legendre spectral elements, p = 24."""
    pipe = StraightPipe(beta=0.2, gamma=10.0)
    return float(classical_critical_velocity(pipe, v_max=10.0, method="legendre", n=24).v_cr)


def _curved_reference(spec: str) -> float:
    """v_cr in 3-D of the paper's case at alpha = pi/2 on the finite elements ``spec``."""
    model = PipeModel(discretization_from_name(spec), Params(alpha=math.pi / 2, **PAPER_CASE))
    return float(find_critical_velocity(model, v_max=10.0, planes=PLANES).v_cr)


@register("critical_vs_classical")
def bench_critical_vs_classical(quick: bool = False) -> dict:
    """CPU seconds of ``fempipe critical`` and of the classical baseline, errors, their ratio."""
    runs = 1 if quick else 7
    ref = _classical_reference()
    fem = ["-m", "fempipe", "critical", *REFERENCE_ARGS, "--json"]
    base = [str(BASELINE), "--beta", "0.2", "--gamma", "10", "--mu", "0", "--v-max", "10"]
    curved_spec = "P3:32" if quick else "P3:64"
    curved_ref = _curved_reference(curved_spec)
    curved = ["-m", "fempipe", "critical", *CURVED_ARGS, "--json"]
    as_written, one_thread = _blas_env(False), _blas_env(True)
    rows, times = _rows(
        [
            ("fempipe critical (alpha 0, P3:16)", fem, ref, None),
            ("baseline, 40 beam modes", [*base, "--n", "40"], ref, as_written),
            ("baseline, 20 beam modes", [*base, "--n", "20"], ref, as_written),
            ("fempipe critical (paper, alpha pi/2)", curved, curved_ref, None),
            ("baseline, 40 beam modes, one BLAS thread", [*base, "--n", "40"], ref, one_thread),
        ],
        runs,
    )
    ratio = rows[0]["cpu_seconds"] / rows[1]["cpu_seconds"]
    ratio1 = rows[0]["cpu_seconds"] / rows[4]["cpu_seconds"]
    paired = [a / b for a, b in zip(times[0], times[1], strict=True)]
    paired1 = [a / b for a, b in zip(times[0], times[4], strict=True)]
    return {
        "runs": runs,
        "order": "in turns: each round runs every command once",
        "bytecode": "cached (PYTHONPYCACHEPREFIX in a temporary directory, one untimed run "
        "per command first)",
        "reference_v_cr": ref,
        "reference": "classical theory, Legendre spectral elements p = 24",
        "curved_reference_v_cr": curved_ref,
        "curved_reference": f"fempipe {curved_spec}",
        "ratio_fempipe_over_baseline40": round(ratio, 3),
        "ratio_by_round": [round(r, 3) for r in paired],
        "ratio_one_thread": round(ratio1, 3),
        "ratio_by_round_one_thread": [round(r, 3) for r in paired1],
        "target_ratio": TARGET_RATIO,
        "meets_target": ratio <= TARGET_RATIO,
        "meets_target_one_thread": ratio1 <= TARGET_RATIO,
        "table": rows,
    }
