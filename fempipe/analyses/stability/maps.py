"""Parallel sweeps: v_cr against alpha (Fig. 6) and root loci of several parameter points."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, replace

import numpy as np

from fempipe.core.parallel import run_tasks
from fempipe.model.params import VARIANT_FIELDS, Params
from fempipe.model.plane.operators import PipeModel

from .analysis import analyse_stability, find_critical_velocity
from .events import StabilityResult
from .linear import PLANES
from .tracking import RootLocus, trace_root_locus

#: The keys of a point of a planar map (``planar=True``), and those a map in both planes
#: adds: each plane's v_cr, frequency, type, mode and first flutter, and the first plane.
PLANAR_KEYS = ("v_cr", "type", "frequency", "mode", "v_flutter")
PLANE_KEYS = (
    *(
        f"{k}_{plane}"
        for plane in ("in_plane", "out_of_plane")
        for k in ("v_cr", "frequency", "type", "mode", "v_flutter")
    ),
    "first_plane",
)


def _by_plane(res) -> dict[str, StabilityResult]:
    if isinstance(res, StabilityResult):
        return {"in_plane": res}
    return {"in_plane": res.in_plane, "out_of_plane": res.out_of_plane}


def _map_point(disc, params: Params, v_max: float, options: dict, planar: bool = False) -> dict:
    """One point: v_cr in the plane (``planar``) or in both planes, and the first flutter."""
    model = PipeModel(disc, params)
    planes = ("in",) if planar else PLANES
    res = find_critical_velocity(model, v_max, planes=planes, **options)
    per = _by_plane(res)
    flutter = {k: r.v_flutter for k, r in per.items()}
    n_spectra = res.n_spectra
    if any(r.critical is not None and r.critical.at_start for r in per.values()):
        # Unstable from the start (the straight column at alpha = pi): follow the branch
        # to the end for that plane's first flutter (what Fig. 6 shows there).
        opts = {**options, "stop_at_first": False, "follow_bifurcations": False}
        full = _by_plane(analyse_stability(model, v_max, planes=planes, **opts))
        n_spectra += sum(r.n_spectra for r in full.values())
        for k, r in per.items():
            if r.critical is not None and r.critical.at_start:
                flutter[k] = full[k].v_flutter
    c = res.critical
    vf = [v for v in flutter.values() if v is not None]
    out = {
        "v_cr": res.v_cr,
        "type": None if c is None else c.type,
        "frequency": None if c is None else c.frequency,
        "mode": None if c is None else c.mode,
        "v_flutter": min(vf) if vf else None,
        "n_spectra": n_spectra,
    }
    if planar:
        return out
    for k, r in per.items():
        ck = r.critical
        out[f"v_cr_{k}"] = r.v_cr
        out[f"frequency_{k}"] = None if ck is None else ck.frequency
        out[f"type_{k}"] = None if ck is None else ck.type
        out[f"mode_{k}"] = None if ck is None else ck.mode
        out[f"v_flutter_{k}"] = flutter[k]
    out["first_plane"] = None if c is None else c.plane
    return out


@dataclass(frozen=True)
class StabilityMap:
    """v_cr against alpha for several (beta, gamma) curves (Fig. 6).

    Attributes
    ----------
    points : list of list of dict
        ``points[c][a]``: the keys of :data:`PLANAR_KEYS` (or ``error``); in both planes those
        of the first loss of stability plus :data:`PLANE_KEYS`.
    planar : bool
        The paper's planar model alone.
    """

    alphas: np.ndarray
    curves: tuple
    base: Params
    v_max: float
    discretization: dict
    points: list
    planar: bool = False

    def array(self, key: str = "v_cr") -> np.ndarray:
        """``key`` as an array, shape (n_curves, n_alpha); NaN where missing."""
        out = np.full((len(self.curves), self.alphas.size), np.nan)
        for c, row in enumerate(self.points):
            for a, pt in enumerate(row):
                x = pt.get(key)
                if isinstance(x, (int, float)) and x is not None:
                    out[c, a] = x
        return out

    def rows(self) -> list[dict]:
        """Flat rows (one per curve and alpha) for CSV."""
        rows = []
        for (beta, gamma), row in zip(self.curves, self.points, strict=True):
            for alpha, pt in zip(self.alphas, row, strict=True):
                row = {"alpha": float(alpha), "beta": beta, "gamma": gamma}
                row.update({k: pt.get(k) for k in PLANAR_KEYS})
                row["error"] = pt.get("error")
                if not self.planar:
                    row.update({k: pt.get(k) for k in PLANE_KEYS})
                rows.append(row)
        return rows

    def to_dict(self) -> dict:
        variants = {k: x for k, x in self.base.to_dict().items() if k in VARIANT_FIELDS}
        return {
            "alphas": self.alphas.tolist(),
            "curves": [{"beta": b, "gamma": g} for b, g in self.curves],
            "mu": self.base.mu,
            **variants,
            "v_max": self.v_max,
            "discretization": self.discretization,
            "points": self.rows(),
        }


def map_stability(
    disc,
    alphas: Sequence[float],
    curves: Sequence[tuple[float, float]],
    *,
    mu: float = 5e-3,
    v_max: float = 10.0,
    variants: Mapping | None = None,
    workers: int | None = None,
    executor: Executor | None = None,
    callback: Callable[[int, int, object], None] | None = None,
    planar: bool = False,
    **options,
) -> StabilityMap:
    """v_cr against alpha for each (beta, gamma) in ``curves``, in parallel, as in Fig 6.

    Each point is a :func:`find_critical_velocity` in both planes (``planar``: in the plane);
    ``options`` passed on (``ds_max`` default 0.2); a failed point keeps its error; ``variants``:
    the variant fields of every point's :class:`~fempipe.model.params.Params`.
    """
    alphas = np.asarray([float(a) for a in alphas])
    curves = tuple((float(b), float(g)) for b, g in curves)
    options.setdefault("ds_max", 0.2)
    if alphas.size == 0 or not curves:
        raise ValueError("need at least one alpha and one (beta, gamma) curve")
    variants = dict(variants or {})
    unknown = set(variants) - set(VARIANT_FIELDS)
    if unknown:
        raise ValueError(
            f"variants are {', '.join(VARIANT_FIELDS)}; got {', '.join(sorted(unknown))}"
        )
    base = Params(alpha=0.0, beta=curves[0][0], gamma=curves[0][1], mu=mu, **variants)
    tasks = []
    for beta, gamma in curves:
        for a in alphas:
            p = replace(base, alpha=a, beta=beta, gamma=gamma, v=0.0)
            tasks.append((disc, p, v_max, options, planar))
    out = run_tasks(_map_point, tasks, workers=workers, executor=executor, callback=callback)
    out = [r if isinstance(r, dict) else {"v_cr": None, "error": str(r)} for r in out]
    points = [out[c * alphas.size : (c + 1) * alphas.size] for c in range(len(curves))]
    return StabilityMap(
        alphas=alphas,
        curves=curves,
        base=base,
        v_max=float(v_max),
        discretization=disc.to_dict(),
        points=points,
        planar=bool(planar),
    )


def _locus_task(disc, params: Params, values, options: dict) -> RootLocus:
    return trace_root_locus(PipeModel(disc, params), values, **options)


def trace_root_loci(
    disc,
    params: Sequence[Params],
    values: Sequence[float],
    *,
    workers: int | None = None,
    executor: Executor | None = None,
    callback: Callable[[int, int, object], None] | None = None,
    **options,
) -> list:
    """:func:`trace_root_locus` of several parameter points (Fig. 5), in parallel: a list of
    RootLocus (or the exception of a failed point)."""
    tasks = [(disc, p, list(values), options) for p in params]
    return run_tasks(_locus_task, tasks, workers=workers, executor=executor, callback=callback)
