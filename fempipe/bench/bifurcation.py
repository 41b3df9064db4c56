"""Benchmarks ``fig07_continuation`` and ``fig08_10_continuation``, as fresh processes."""

from __future__ import annotations

from fempipe.bench.harness import child_json, register

#: Whole-process CPU target of Fig. 7 by continuation.
FIG07_TARGET_S = 20.0
#: Whole-process CPU target of Figs. 8-10 (four inclinations) by continuation.
FIG08_10_TARGET_S = 120.0
FIG07 = ["bifurcation", "--v", "5:12:36", "--json", "--quiet"]
FIG08_10 = [*FIG07, "--alphas", "pi/4,pi/2,3pi/4,pi"]


def _agreement(cont: dict, sweep: dict) -> dict:
    """Largest |difference| of period and tip extrema between continued stable orbits and swept attractors."""
    cyc = {}
    for p in cont["points"]:
        if p["direction"] == "continuation" and p["requested"] and p["stable"]:
            cyc[(round(p["alpha"], 12), round(p["v"], 9))] = p
    worst = {"period": 0.0, "eta_tip": 0.0, "X_tip": 0.0, "Z_tip": 0.0}
    n = missing = 0
    for p in sweep["points"]:
        if p["attractor"] != "periodic":
            continue
        q = cyc.get((round(p["alpha"], 12), round(p["v"], 9)))
        if q is None:
            missing += 1
            continue
        n += 1
        worst["period"] = max(worst["period"], abs(p["period"] - q["period"]))
        for k in ("eta_tip", "X_tip", "Z_tip"):
            worst[k] = max(worst[k], max(abs(a - b) for a, b in zip(p[k], q[k], strict=True)))
    return {"compared": n, "sweep_cycles_without_stable_orbit": missing, "max_difference": worst}


def _summary(d: dict) -> dict:
    return {
        "n_points": len(d["points"]),
        "n_orbits": sum(p["direction"] == "continuation" for p in d["points"]),
        "branches": [
            {k: b[k] for k in ("alpha", "name", "end_reason", "steps", "newton_iterations")}
            for b in d["branches"]
        ],
        "special_points": d["special_points"],
        "errors": d["errors"],
    }


def _bench(argv: list[str], target: float, name: str, with_sweep: bool) -> dict:
    cpu, d = child_json(["-m", "fempipe", *argv])
    out = {
        "name": name,
        "command": "fempipe " + " ".join(argv),
        "cpu_s": cpu,
        "target_cpu_s": target,
        "meets_target": cpu < target,
        **_summary(d),
    }
    if with_sweep:
        cpu_sweep, sweep = child_json(["-m", "fempipe", *argv, "--method", "sweep"])
        out["sweep_cpu_s"] = cpu_sweep
        out["sweep_over_continuation"] = cpu_sweep / cpu
        out["agreement_with_sweep"] = _agreement(d, sweep)
    return out


@register("fig07_continuation")
def fig07_continuation(quick: bool = False) -> dict:
    """Fig. 7 by continuation, whole process; with the sweep for comparison unless quick."""
    return _bench(FIG07, FIG07_TARGET_S, "fig07_continuation", with_sweep=not quick)


@register("fig08_10_continuation")
def fig08_10_continuation(quick: bool = False) -> dict:
    """Figs. 8-10 by continuation (four inclinations), whole process, no sweep."""
    del quick
    return _bench(FIG08_10, FIG08_10_TARGET_S, "fig08_10_continuation", with_sweep=False)
