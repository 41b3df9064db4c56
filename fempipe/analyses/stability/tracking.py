"""Mode numbers by continuity along a path of static states, and root loci (Fig. 5).

The numbering rule: docs/theory/stability.md, "Mode numbers".
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from fempipe.analyses.statics import (
    NewtonError,
    continue_static,
    solve_path,
    solve_sagged,
    solve_static,
)
from fempipe.core.matching import assignment
from fempipe.core.parallel import single_blas
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel

from .canonical import RESOLUTION_TOL, Resolution, resolution
from .classified import (
    STABILITY_TOL,
    ClassifiedSpectrum,
    canonical_labels,
    classify_inherited,
    classify_spectrum,
    eigenvalue_dict,
    mode_order,
)
from .linear import plane_models, straight_pencil

log = logging.getLogger(__name__)

#: Mode numbers up to which tracking ambiguities are refined (labels of higher
#: modes, heavily damped for mu > 0, may swap without affecting any event).
LABEL_MODES = 8


class ModeTracker:
    """Mode numbers carried by continuity: ``labels[j]`` of the tracked eigenvalue j, whose
    index into the first state's spectrum is ``first_idx[j]``."""

    def __init__(self, labels: np.ndarray, first_idx: np.ndarray) -> None:
        self.labels = np.asarray(labels, dtype=int)
        self.first_idx = np.asarray(first_idx, dtype=int)

    @classmethod
    def canonical(cls, first: ClassifiedSpectrum) -> ModeTracker:
        """Every resolved eigenvalue of ``first``, numbered by canonical assignment."""
        idx = np.flatnonzero(first.resolved)
        labels = canonical_labels(first, idx)
        o = mode_order(first.lam[idx], labels)
        return cls(labels[o], idx[o])

    def match(self, new: ClassifiedSpectrum, pred: np.ndarray):
        """Indices in ``new`` of the tracked eigenvalues, and which matches are ambiguous."""
        D = np.abs(pred[:, None] - new.lam[None, :])
        rows, cols = assignment(D)
        idx = np.empty(pred.size, dtype=int)
        idx[rows] = cols
        d1 = D[np.arange(pred.size), idx]
        # Distance to the nearest other candidate that is not the same mode's
        # partner (swapping a conjugate pair or the two roots of one mode is harmless).
        owner = np.full(new.lam.size, -1)
        owner[idx] = self.labels
        other = owner[None, :] != self.labels[:, None]
        D2 = np.where(other, D, np.inf)
        d2 = D2.min(axis=1)
        relevant = (self.labels <= LABEL_MODES) | (new.lam[idx].real > -1.0)
        ambiguous = relevant & (d1 > 0.35 * d2)
        return idx, ambiguous


def _predict(samples: list[tuple[ClassifiedSpectrum, np.ndarray]], s: float) -> np.ndarray:
    """Linear prediction of the tracked eigenvalues at position s."""
    e1, i1 = samples[-1]
    if len(samples) < 2 or samples[-2][0].s == e1.s:
        return e1.lam[i1]
    e0, i0 = samples[-2]
    return e1.lam[i1] + (s - e1.s) / (e1.s - e0.s) * (e1.lam[i1] - e0.lam[i0])


def state_l2(model: PipeModel, dq: np.ndarray) -> float:
    """(int_0^1 theta_dq^2 dxi)^(1/2): with |dv|, the distance between states along a path."""
    th = model.disc.Phi @ dq
    return float(np.sqrt(model.w @ th**2))


class TrackedPath:
    """Spectra along a sequence of static states, with tracking and refinement."""

    def __init__(
        self, model: PipeModel, res: Resolution, method: str, max_depth: int = 6, inherit=False
    ) -> None:
        # inherit: straight states may inherit their classification (classify_inherited).
        self.model, self.res, self.method = model, res, method
        self.inherit, self.max_depth = inherit, max_depth
        self.samples: list[tuple[ClassifiedSpectrum, np.ndarray]] = []
        self.tracker: ModeTracker | None = None
        self.n_spectra = 0

    def analyse(self, q: np.ndarray, v: float) -> ClassifiedSpectrum:
        self.n_spectra += 1
        m = self.model.with_params(replace(self.model.params, v=v))
        # At the straight state the matrices are known functions of v (StraightPencil).
        if q.any():
            return classify_spectrum(m, q, self.res, self.method)
        matrices = straight_pencil(m).matrices(v)
        if self.inherit:
            # (an inherited spectrum is a straight state: no test of its q)
            near = [e for e, _ in self.samples if e.origin_v is not None or not e.q.any()]
            if near:
                ref = min(near, key=lambda e: abs(e.v - v))
                return classify_inherited(m, q, self.res, self.method, matrices, ref)
        return classify_spectrum(m, q, self.res, self.method, matrices)

    def static_between(
        self, a: ClassifiedSpectrum, b: ClassifiedSpectrum, v: float
    ) -> np.ndarray | None:
        """The static state at v between samples a and b (one monotone piece in v), or None."""
        if a.v == b.v:
            return None
        t = (v - a.v) / (b.v - a.v)
        m = self.model.with_params(replace(self.model.params, v=v))
        guess = a.q + t * (b.q - a.q)
        # An exact guess (the straight pipe at alpha = 0, pi) is kept: at a branch point
        # the Jacobian is singular and Newton would fail.
        p = m.params
        if np.linalg.norm(m.static_residual(guess)) <= 1e-13 * (1.0 + p.gamma + p.v**2):
            return guess
        try:
            return solve_static(m, q0=guess).q
        except NewtonError:
            return None

    def add(self, e: ClassifiedSpectrum, depth: int = 0) -> None:
        """Append the next state, halving the step while tracking is ambiguous."""
        if self.tracker is None:
            self.tracker = ModeTracker.canonical(e)
            self.samples.append((e, self.tracker.first_idx))
            return
        prev = self.samples[-1]
        pred = _predict(self.samples, e.s)
        idx, amb = self.tracker.match(e, pred)
        if amb.any() and depth < self.max_depth and not e.fold and not prev[0].fold:
            a = prev[0]
            vm = 0.5 * (a.v + e.v)
            qm = self.static_between(a, e, vm)
            if qm is not None:
                mid = self.analyse(qm, vm)
                mid.s = 0.5 * (a.s + e.s)
                self.add(mid, depth + 1)
                self.add(e, depth + 1)
                return
        self.samples.append((e, idx))

    # -- views ------------------------------------------------------------
    @property
    def labels(self) -> np.ndarray:
        return self.tracker.labels

    def tracked(self) -> np.ndarray:
        """Tracked eigenvalues, shape (n_samples, k)."""
        return np.array([e.lam[i] for e, i in self.samples])

    def start_labelled(self, e: ClassifiedSpectrum, tracker: ModeTracker) -> None:
        """Start at ``e`` with mode numbers given by ``tracker`` (indices into e)."""
        self.tracker = tracker
        self.samples = [(e, tracker.first_idx)]


#: Largest arclength step of the reference path from v = 0 (mode numbers).
REFERENCE_STEP = 1.0


def reference_tracker(model: PipeModel, e: ClassifiedSpectrum, res: Resolution, method: str):
    """(tracker, spectra solved): the mode numbers of ``e``'s resolved eigenvalues, carried
    from v = 0 along its static branch (docs/theory/stability.md, "Mode numbers")."""
    if e.v == 0.0:
        return ModeTracker.canonical(e), 0
    m = model.with_params(replace(model.params, v=e.v))
    back = continue_static(
        m, "v", stop=0.0, q0=e.q, ds=REFERENCE_STEP, ds_max=REFERENCE_STEP, detect=False
    )
    if back.end_reason != "stop":
        log.info(
            "reference path: the branch through v=%.6g ends at v=%.6g (%s); mode numbers "
            "assigned there",
            e.v,
            back.points[-1].value,
            back.end_reason,
        )
    # v = 0 first, e itself last.  Coincident points are dropped: a step of 1e-33
    # followed by a finite one would wreck the linear prediction.
    points = []
    for pt in back.points[::-1][:-1]:
        last = points[-1] if points else None
        if last is None or abs(pt.value - last.value) + state_l2(model, pt.q - last.q) > 1e-8:
            points.append(pt)
    if points and abs(e.v - points[-1].value) + state_l2(model, e.q - points[-1].q) <= 1e-8:
        points.pop()
    path = TrackedPath(model, res, method)
    s, prev = 0.0, None
    for pt in points:
        if prev is not None:
            s += abs(pt.value - prev[1]) + state_l2(model, pt.q - prev[0])
        prev = (pt.q, pt.value)
        x = path.analyse(pt.q, pt.value)
        x.s = s
        path.add(x)
    s += abs(e.v - prev[1]) + state_l2(model, e.q - prev[0]) if prev is not None else 0.0
    target = replace(e, s=s)
    path.add(target)
    last, idx = path.samples[-1]
    if last is not target:  # pragma: no cover - add() always appends its argument last
        raise RuntimeError("reference path: the target state is not the last sample")
    return complete_tracker(e, ModeTracker(path.labels, idx)), path.n_spectra


def complete_tracker(e: ClassifiedSpectrum, tracker: ModeTracker) -> ModeTracker:
    """Add the resolved eigenvalues of e the tracker lacks, numbered on the free canonical
    slots (two per mode) by their eigenvectors."""
    tracked = set(tracker.first_idx.tolist())
    extra = np.array([i for i in np.flatnonzero(e.resolved) if i not in tracked], dtype=int)
    if extra.size == 0:
        return tracker
    n_can = e.weights.shape[0]
    used = np.bincount(tracker.labels - 1, minlength=n_can)[:n_can]
    free = np.maximum(0, 2 - used)
    slots = np.repeat(np.arange(n_can), free)
    cost = -e.weights[:, extra].T[:, slots]
    rows, cols = assignment(cost)
    labels = np.zeros(extra.size, dtype=int)
    labels[rows] = slots[cols] + 1
    return ModeTracker(
        np.concatenate([tracker.labels, labels]), np.concatenate([tracker.first_idx, extra])
    )


@dataclass(frozen=True)
class RootLocus:
    """Eigenvalues against v with mode numbers carried by continuity (Fig. 5).

    Attributes
    ----------
    lam : ndarray of complex, shape (m, k)
        Column j belongs to mode ``modes[j]`` (modes 1..n_modes and every unstable one).
    max_real, theta_tip : ndarray, shape (m,)
        Largest resolved Re lambda; static tip rotation.
    n_spectra : int
        Spectra computed, including those inserted for tracking.
    """

    params: Params
    v: np.ndarray
    lam: np.ndarray
    modes: np.ndarray
    resolved: np.ndarray
    max_real: np.ndarray
    stable: np.ndarray
    theta_tip: np.ndarray
    n_spectra: int
    plane: str = "in"

    @property
    def Omega(self) -> np.ndarray:
        return -1j * self.lam

    def to_dict(self) -> dict:
        p = self.params.to_dict()
        p.pop("v", None)
        points = [
            {
                "v": float(v),
                "stable": bool(self.stable[i]),
                "max_real": float(self.max_real[i]),
                "theta_tip": float(self.theta_tip[i]),
                "eigenvalues": [
                    eigenvalue_dict(self.lam[i, j], int(self.modes[j]))
                    for j in range(self.modes.size)
                    if self.resolved[i, j]
                ],
            }
            for i, v in enumerate(self.v)
        ]
        return {"params": p, "modes": self.modes.tolist(), "points": points}


@single_blas
def trace_root_locus(
    model: PipeModel,
    values: Sequence[float],
    *,
    planes: tuple[str, ...] = ("in",),
    q0: np.ndarray | None = None,
    n_modes: int | None = 6,
    method: str = "auto",
    tolerance: float = RESOLUTION_TOL,
    callback: Callable[[int, float], None] | None = None,
) -> RootLocus | tuple[RootLocus, RootLocus]:
    """Spectra along the static branch at the flow velocities ``values``: a root locus, as in Fig 5.

    Parameters
    ----------
    model : PipeModel
    values : sequence of float
        Flow velocities, in the order the branch is followed.
    planes : tuple of {'in', 'out'}
        In the plane (Eq. (32)) and/or out of it, about the same static states.
    q0 : ndarray, optional
        Static state at ``values[0]`` (default: :func:`~fempipe.analyses.statics.solve_sagged`).
    n_modes : int or None
        Report modes 1..n_modes (None: all resolved) and every mode unstable at some v.
    callback : callable, optional
        ``callback(i, v)`` after each value.

    Returns
    -------
    RootLocus
        ``(in_plane, out_of_plane)`` for ``("in", "out")``.
    """
    models = plane_models(model, planes)
    model = models[0]
    values = [float(x) for x in values]
    if not values:
        raise ValueError("values must contain at least one flow velocity")
    if n_modes is not None and int(n_modes) < 1:
        raise ValueError(f"n_modes must be >= 1 or None, got {n_modes}")
    res = resolution(model.disc, tolerance)
    if res.n_resolved == 0:
        raise ValueError(f"discretization {model.disc.name} resolves no mode; refine it")
    m0 = model.with_params(replace(model.params, v=values[0]))
    states = solve_path(m0, values, q0=solve_sagged(m0).q if q0 is None else q0)
    paths = [TrackedPath(m, res, method) for m in models]
    keep: list[list[int]] = [[] for _ in models]  # sample index of each requested value
    s = 0.0
    for i, sol in enumerate(states):
        if i:
            s += abs(values[i] - values[i - 1]) + state_l2(model, sol.q - states[i - 1].q)
        for m, path, kept in zip(models, paths, keep, strict=True):
            e = path.analyse(sol.q, values[i])
            e.s = s
            if i == 0:
                tracker, n_ref = reference_tracker(m, e, res, method)
                path.n_spectra += n_ref
                path.start_labelled(e, tracker)
            else:
                path.add(e)
            kept.append(len(path.samples) - 1)
        if callback:
            callback(i, values[i])
    tips = np.array([float(model.disc.tip @ st.q) for st in states])
    loci = [
        _locus_of(m, path, kept, m0.params, values, tips, n_modes)
        for m, path, kept in zip(models, paths, keep, strict=True)
    ]
    return loci[0] if len(loci) == 1 else tuple(loci)


def _locus_of(model, path, keep, params, values, tips, n_modes) -> RootLocus:
    lam = path.tracked()[keep]
    resolved = np.array([e.resolved[i] for e, i in path.samples])[keep]
    labels = path.labels
    # Every mode unstable somewhere is listed: the eigenvalue that decides ``stable``.
    unstable = resolved & (lam.real > STABILITY_TOL * np.maximum(1.0, np.abs(lam)))
    cols = np.ones(labels.size, dtype=bool) if n_modes is None else labels <= int(n_modes)
    cols = np.flatnonzero(cols | unstable.any(axis=0))
    cols = cols[np.argsort(labels[cols], kind="stable")]
    return RootLocus(
        params=params,
        v=np.array(values),
        lam=lam[:, cols],
        modes=labels[cols].copy(),
        resolved=resolved[:, cols],
        max_real=np.array([path.samples[k][0].max_real for k in keep]),
        stable=np.array([not path.samples[k][0].unstable.any() for k in keep]),
        theta_tip=tips,
        n_spectra=path.n_spectra,
        plane=model.plane,
    )
