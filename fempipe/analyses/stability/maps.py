"""Parallel sweeps: v_cr against alpha (Fig. 6) and root loci of several parameter points."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, replace

import numpy as np

from fempipe.core.parallel import run_tasks
from fempipe.model.operators import PipeModel
from fempipe.model.params import VARIANT_FIELDS, Params

from .analysis import critical_velocity, stability_analysis
from .spatial import spatial_critical_velocity, spatial_stability_analysis
from .tracking import RootLocus, root_locus

#: The keys of a point of a planar map (``planar=True``), and those a map in
#: three dimensions adds: each plane's critical velocity, frequency, type,
#: mode and first flutter, and the plane that loses stability first.
PLANAR_KEYS = ("v_cr", "type", "frequency", "mode", "v_flutter")
PLANE_KEYS = tuple(
    f"{k}_{plane}"
    for plane in ("in_plane", "out_of_plane")
    for k in ("v_cr", "frequency", "type", "mode", "v_flutter")
)
SPATIAL_KEYS = (*PLANE_KEYS, "first_plane")


def _map_point(disc, params: Params, v_max: float, options: dict, planar: bool = False) -> dict:
    if planar:
        return _planar_point(disc, params, v_max, options)
    return _spatial_point(disc, params, v_max, options)


def _planar_point(disc, params: Params, v_max: float, options: dict) -> dict:
    model = PipeModel(disc, params)
    res = critical_velocity(model, v_max, **options)
    c = res.critical
    if c is not None and c.at_start:
        # Unstable from the start (the straight column at alpha = pi): follow the
        # branch to the end for its first flutter (what Fig. 6 shows there).
        full = stability_analysis(
            model, v_max, **{**options, "stop_at_first": False, "follow_bifurcations": False}
        )
        res = replace(res, v_flutter=full.v_flutter, n_spectra=res.n_spectra + full.n_spectra)
    return {
        "v_cr": res.v_cr,
        "type": None if c is None else c.type,
        "frequency": None if c is None else c.frequency,
        "mode": None if c is None else c.mode,
        "v_flutter": res.v_flutter,
        "n_spectra": res.n_spectra,
    }


def _spatial_point(disc, params: Params, v_max: float, options: dict) -> dict:
    """One point in three dimensions: :func:`spatial_critical_velocity` (one static branch,
    both planes), each plane's first loss and the first of the two."""
    model = PipeModel(disc, params)
    res = spatial_critical_velocity(model, v_max, **options)
    planes = {"in_plane": res.in_plane, "out_of_plane": res.out_of_plane}
    flutter = {k: r.v_flutter for k, r in planes.items()}
    n_spectra = res.n_spectra
    if any(r.critical is not None and r.critical.at_start for r in planes.values()):
        # Unstable from the start in a plane: follow the branch to the end for
        # that plane's first flutter (as the planar map does).
        full = spatial_stability_analysis(
            model, v_max, **{**options, "stop_at_first": False, "follow_bifurcations": False}
        )
        n_spectra += full.n_spectra
        for k, r in planes.items():
            if r.critical is not None and r.critical.at_start:
                flutter[k] = getattr(full, k).v_flutter
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
    for k, r in planes.items():
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
    alphas : ndarray, shape (n_alpha,)
    curves : tuple of (beta, gamma)
    base : Params
        mu, the variants of the pipe (end mass, dampings, springs) and the
        defaults.
    v_max : float
        Upper end of the searched range (v_cr is None if stable up to it).
    points : list of list of dict
        ``points[c][a]``: v_cr, type, frequency, mode, v_flutter (or error);
        in three dimensions v_cr, type, frequency, mode are those of the first
        loss of stability of either plane, v_flutter the first flutter of
        either, and each plane's values are added (:data:`SPATIAL_KEYS`:
        ``v_cr_in_plane``, ``v_cr_out_of_plane``, ``frequency_in_plane``, ...,
        ``first_plane``: "in", "out", or None if stable).
    planar : bool
        The paper's planar model alone (no out-of-plane analysis).
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
                    row.update({k: pt.get(k) for k in SPATIAL_KEYS})
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


def stability_map(
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
    """v_cr against alpha for each (beta, gamma) in ``curves``, computed in parallel.

    The stability map of the paper's Fig. 6.

    Each point is an independent :func:`~fempipe.analyses.stability.spatial_critical_velocity`
    (gravity loading, continuation in v, the first loss of stability in the
    plane of the static state and out of it along the same branch; v_cr the
    first of the two), or with ``planar`` the paper's planar
    :func:`critical_velocity` alone; ``options`` are passed on
    (``ds_max`` defaults to 0.2 here: Brent locates v_cr to 1e-10 whatever the
    sampling, and the tracking and peak checks refine where needed).
    A point that fails is recorded with its error and does not stop the others.
    ``variants`` gives the variant fields of :class:`~fempipe.model.params.Params`
    (``end_mass``, ``external_damping``, ``hysteretic_damping``, ``springs``)
    of every point; default none (the paper's pipe).
    """
    alphas = np.asarray([float(a) for a in alphas])
    curves = tuple((float(b), float(g)) for b, g in curves)
    # v_cr only: continuation steps of 0.2 (the 37-point curve of Fig. 6 is the
    # same to 3e-11 as with 0.1, and cheaper).
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
    points = []
    for c in range(len(curves)):
        row = []
        for a in range(alphas.size):
            r = out[c * alphas.size + a]
            row.append(r if isinstance(r, dict) else {"v_cr": None, "error": str(r)})
        points.append(row)
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
    return root_locus(PipeModel(disc, params), values, **options)


def root_loci(
    disc,
    params: Sequence[Params],
    values: Sequence[float],
    *,
    workers: int | None = None,
    executor: Executor | None = None,
    callback: Callable[[int, int, object], None] | None = None,
    **options,
) -> list:
    """:func:`root_locus` for several parameter points (e.g. the four alphas of Fig. 5), in parallel.

    Returns a list of RootLocus (or the exception of a failed point).
    """
    tasks = [(disc, p, list(values), options) for p in params]
    return run_tasks(_locus_task, tasks, workers=workers, executor=executor, callback=callback)
