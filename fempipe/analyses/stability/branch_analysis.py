"""Spectra, tracking and events along one static branch: crossings located by Brent, folds.

:class:`BranchAnalysis` samples the spectra along a continuation branch,
carries the mode numbers, checks extrema of Re lambda between samples and
locates every crossing of Re lambda = 0 (docs/theory/stability.md, "Stability
events"); its results are :class:`~fempipe.analyses.stability.events.BranchStability`.
"""

from __future__ import annotations

import copy
import logging
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from fempipe.analyses.statics import NewtonError
from fempipe.core.rootfinding import brentq
from fempipe.model.plane.operators import PipeModel

from .canonical import Resolution
from .chunked_branch import ChunkedBranch
from .classified import STABILITY_TOL, ClassifiedSpectrum
from .events import BranchStability, StabilityEvent
from .tracking import ModeTracker, TrackedPath, complete_tracker, reference_tracker, state_l2

log = logging.getLogger(__name__)

#: Brent tolerance on v for every located event (1e-10, well below the 1e-8
#: at which v_cr is compared with independent computations).
EVENT_XTOL = 1e-10
#: An eigenvalue with |Im| <= IMAG_TOL * max(1, |lambda|) at a crossing is real.
IMAG_TOL = 1e-7


def _unstable_count(e: ClassifiedSpectrum) -> int:
    return int(e.unstable.sum())


def peak_candidates(x: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """The tracked eigenvalues (``lam`` (3, k) at the samples ``x``) that may pass the extremum test
    of ``BranchAnalysis._peak``: its tests vectorized with a margin, the exact one left to those.
    """
    r = lam.real
    tol = STABILITY_TOL * np.maximum(1.0, np.abs(lam))
    states = np.where(r > tol, 1, np.where(r < -tol, -1, 0))
    up = states > 0
    same = (up == up[0]).all(axis=0)
    unstable = up[0]
    keep = same & (unstable | (states == -1).any(axis=0))
    # The parabola through the three samples in t = (v - v_m)/h.
    h = 0.5 * (x.max() - x.min())
    t0, t2 = (x[0] - x[1]) / h, (x[2] - x[1]) / h
    d0, d2 = r[0] - r[1], r[2] - r[1]
    det = t0 * t2 * (t0 - t2)
    c2 = (d0 * t2 - d2 * t0) / det
    c1 = (d2 * t0 * t0 - d0 * t2 * t2) / det
    spread = np.abs(r[1] - r[0]) + np.abs(r[2] - r[1])
    slack = 1e-9 * (np.abs(r).max(axis=0) + spread) + 1e-300
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        points_to_zero = np.where(unstable, c2 > -slack, c2 < slack)
        tx = -c1 / (2.0 * c2)
        inside = (tx > min(t0, t2) - 1e-6) & (tx < max(t0, t2) + 1e-6)
        ext = r[1] + c1 * tx + c2 * tx * tx
        near = np.where(unstable, ext <= 0.5 * spread + slack, ext >= -0.5 * spread - slack)
    # Non-finite values (c2 = 0) are left to the exact test.
    test = ~np.isfinite(tx) | (points_to_zero & inside & near)
    return np.flatnonzero(keep & test)


def _state_sign(lam: complex) -> int:
    """+1 unstable, -1 stable, 0 marginal (|Re| within round-off)."""
    tol = STABILITY_TOL * max(1.0, abs(lam))
    if lam.real > tol:
        return 1
    if lam.real < -tol:
        return -1
    return 0


class BranchAnalysis:
    """Spectra, tracking and events along one continuation branch, in three passes: a spectrum at
    every point; extrema of Re lambda towards zero between samples maximised (and made samples if
    they cross); every sign change located by Brent (docs/theory/stability.md, "Stability events").
    """

    def __init__(
        self,
        model: PipeModel,
        res: Resolution,
        branch: ChunkedBranch,
        name: str,
        v_range: tuple[float, float],
        method: str,
        stop_at_first: bool = False,
        callback: Callable[[str, float], None] | None = None,
        parent: BranchAnalysis | None = None,
        stride: int = 1,
    ) -> None:
        # Every stride-th continuation point is a sample (folds and the last
        # point always are); the tracker inserts states where it is unsure.
        self.model, self.stride, self.res, self.method = model, int(stride), res, method
        self.branch, self.name, self.parent = branch, name, parent
        self.v_lo, self.v_hi = v_range
        self.path = TrackedPath(model, res, method, inherit=True)
        self.stop_at_first, self.callback = stop_at_first, callback
        # (position s, event, unstable count before, after) in branch order
        self.events: list[tuple[float, StabilityEvent, int, int]] = []

    # -- pass 1: samples ----------------------------------------------------
    def run(self) -> None:
        s, prev, skipped = 0.0, None, None
        for k, (q, v, is_fold) in enumerate(self.branch.iter_points()):
            if prev is not None:
                s += abs(v - prev[1]) + state_l2(self.model, q - prev[0])
            prev = (q, v)
            if k % self.stride and not is_fold:
                skipped = (q, v, s)
                continue
            skipped = None
            if self._sample(q, v, s, is_fold):
                break
        else:
            if skipped is not None:  # the branch's last point is always a sample
                self._sample(*skipped, False)
        self._peaks()
        samples = self.path.samples
        for k in range(1, len(samples)):
            self._segment(k)
            if samples[k][0].fold:
                self._fold_event(k)
        self._start_events()
        self.events.sort(key=lambda x: x[0])

    def as_plane(self, model: PipeModel) -> BranchAnalysis:
        """This analysis as that of ``model``'s plane: the same samples and events (for a
        branch on which the two planes' problems are the same matrices)."""
        other = copy.copy(self)
        other.model = model
        other.events = [(s, replace(ev, plane=model.plane), a, b) for s, ev, a, b in self.events]
        return other

    def _sample(self, q: np.ndarray, v: float, s: float, is_fold: bool) -> bool:
        """Analyse one point of the branch; True when the analysis stops there."""
        e = self.path.analyse(q, v)
        e.s, e.fold = s, is_fold
        if self.path.tracker is None:
            self._number(e)
        else:
            self.path.add(e)
        if self.callback:
            self.callback(self.name, v)
        return bool(self.stop_at_first and _unstable_count(e) > 0)

    def _number(self, first: ClassifiedSpectrum) -> None:
        """Mode numbers at the first state: from v = 0, or from the parent's nearest sample."""
        if self.parent is None:
            tracker, n = reference_tracker(self.model, first, self.res, self.method)
        else:
            tracker, n = self.parent.carry_to(first)
        self.path.n_spectra += n
        self.path.start_labelled(first, tracker)

    def carry_to(self, e: ClassifiedSpectrum) -> tuple[ModeTracker, int]:
        """Mode numbers of e (a state near this branch) by continuity from the nearest sample."""
        dist = [abs(x.v - e.v) + state_l2(self.model, x.q - e.q) for x, _ in self.path.samples]
        k = int(np.argmin(dist))
        ref, idx = self.path.samples[k]
        path = TrackedPath(self.model, self.res, self.method)
        path.start_labelled(ref, ModeTracker(self.path.labels, idx))
        path.add(replace(e, s=ref.s + dist[k]))
        return complete_tracker(e, ModeTracker(path.labels, path.samples[-1][1])), path.n_spectra

    def _retrack(self, eigs: list[ClassifiedSpectrum]) -> None:
        self.path.samples = [(eigs[0], self.path.tracker.first_idx)]
        for e in eigs[1:]:
            self.path.add(e, depth=self.path.max_depth)

    # -- pass 2: extrema of Re lambda between samples ----------------------
    def _peaks(self, max_inserts: int = 20) -> None:
        inserted = 0
        k = 2
        while k < len(self.path.samples) and inserted < max_inserts:
            e = self._peak(k)
            if e is None:
                k += 1
                continue
            eigs = [x for x, _ in self.path.samples]
            eigs.insert(k - 1 if e.s < eigs[k - 1].s else k, e)
            self._retrack(eigs)
            inserted += 1

    def _peak(self, k: int) -> ClassifiedSpectrum | None:
        """A sample where a tracked Re lambda touches zero between samples k-2 and k, or None."""
        (a, ia), (m, im), (b, ib) = self.path.samples[k - 2 : k + 1]
        if m.fold or a.fold or b.fold or not (a.v < m.v < b.v or a.v > m.v > b.v):
            return None
        x = np.array([a.v, m.v, b.v])
        for j in peak_candidates(x, np.array([a.lam[ia], m.lam[im], b.lam[ib]])):
            lams = (a.lam[ia[j]], m.lam[im[j]], b.lam[ib[j]])
            states = [_state_sign(lam) for lam in lams]
            signs = [s > 0 for s in states]
            if len(set(signs)) != 1:
                continue  # a crossing: located in pass 3
            unstable = signs[0]
            if not unstable and -1 not in states:
                continue  # on the imaginary axis to round-off (undamped): nothing to refine
            r = np.array([lam.real for lam in lams])
            # The parabola through the three samples, in t = (v - v_m)/h so that
            # the Vandermonde system stays well conditioned for close samples.
            h = 0.5 * (x.max() - x.min())
            c = np.polyfit((x - x[1]) / h, r, 2)
            if c[0] == 0 or (c[0] < 0) == unstable:
                continue  # the extremum points away from zero
            tx = -c[1] / (2 * c[0])
            vx = x[1] + h * tx
            if not x.min() < vx < x.max():
                continue
            ext, spread = np.polyval(c, tx), abs(r[1] - r[0]) + abs(r[2] - r[1])
            if (not unstable and ext < -0.5 * spread) or (unstable and ext > 0.5 * spread):
                continue
            sgn = -1.0 if unstable else 1.0
            lo, hi = (a, b) if a.v < b.v else (b, a)
            ilo, ihi = (ia[j], ib[j]) if a.v < b.v else (ib[j], ia[j])

            def g(v: float, lo=lo, hi=hi, ilo=ilo, ihi=ihi, sgn=sgn) -> float:
                e, kk = self._eig_at(lo, hi, ilo, ihi, v)
                return -sgn * e.lam[kk].real

            from scipy.optimize import minimize_scalar  # rare: a narrow window

            opt = minimize_scalar(g, bounds=(lo.v, hi.v), method="bounded", options={"xatol": 1e-7})
            e, kk = self._eig_at(lo, hi, ilo, ihi, float(opt.x))
            if (_state_sign(e.lam[kk]) > 0) != unstable:
                e.s = lo.s + (hi.s - lo.s) * (float(opt.x) - lo.v) / (hi.v - lo.v)
                log.info("branch %s: narrow window of Re lambda > 0 near v=%.6g", self.name, opt.x)
                return e
        return None

    # -- pass 3: events -----------------------------------------------------
    def _eig_at(
        self, a: ClassifiedSpectrum, b: ClassifiedSpectrum, ia: int, ib: int, v: float
    ) -> tuple[ClassifiedSpectrum, int]:
        """The tracked eigenvalue at v between samples a and b (nearest the linear prediction)."""
        q = self.path.static_between(a, b, v)
        if q is None:
            raise NewtonError(
                f"static state not found at v={v:.10g} while locating a stability event on "
                f"branch {self.name}",
                params=replace(self.model.params, v=v),
                iterations=0,
                residual=float("nan"),
            )
        e = self.path.analyse(q, v)
        pred = a.lam[ia] + (v - a.v) / (b.v - a.v) * (b.lam[ib] - a.lam[ia])
        cand = np.flatnonzero(e.resolved) if e.resolved.any() else np.arange(e.lam.size)
        return e, int(cand[np.argmin(np.abs(e.lam[cand] - pred))])

    def _locate(
        self, a: ClassifiedSpectrum, b: ClassifiedSpectrum, ia: int, ib: int
    ) -> tuple[float, complex]:
        """Brent on Re lambda of one tracked eigenvalue between samples a and b."""
        shift = 0.0
        # A marginal end (|Re| within round-off: an undamped problem) means the
        # onset is a collision, Re ~ sqrt(v - v_c): locating Re = tol instead
        # of 0 moves v by ~tol^2, far below the 1e-10 asked of Brent.
        for lam in (a.lam[ia], b.lam[ib]):
            if _state_sign(lam) == 0:
                shift = STABILITY_TOL * max(1.0, abs(lam))
        fa, fb = a.lam[ia].real - shift, b.lam[ib].real - shift
        if fa == 0.0 or fb == 0.0 or np.sign(fa) == np.sign(fb):
            e, i = (a, ia) if abs(fa) <= abs(fb) else (b, ib)
            return e.v, complex(e.lam[i])
        found: dict[float, complex] = {}

        def f(v: float) -> float:
            if v == a.v:
                return fa
            if v == b.v:
                return fb
            e, k = self._eig_at(a, b, ia, ib, v)
            found[v] = e.lam[k]
            return float(e.lam[k].real - shift)

        try:
            v0 = brentq(f, a.v, b.v, xtol=EVENT_XTOL, rtol=4 * np.finfo(float).eps)
        except NewtonError as exc:
            # No static state near the branch inside the bracket: the branch
            # crosses a gap, as at an imperfect pitchfork (alpha a hair off 0
            # or pi), where the continuation steps over the imperfection's
            # fold.  The event lies in the last bracket; place it mid-way.
            below = [w for w, lam in found.items() if np.sign(lam.real - shift) == np.sign(fa)]
            above = [w for w, lam in found.items() if np.sign(lam.real - shift) == np.sign(fb)]
            # The innermost values on each side: nearest the other end.
            lo = min(below, key=lambda w: abs(w - b.v), default=a.v)
            hi = min(above, key=lambda w: abs(w - a.v), default=b.v)
            v0 = 0.5 * (lo + hi)
            log.warning(
                "branch %s: %s; the stability event is placed at v = %.10g, the middle of "
                "the last bracket [%.10g, %.10g] (located to %.1e, not %.0e): the branch may "
                "pass an imperfect bifurcation there",
                self.name,
                exc,
                v0,
                min(lo, hi),
                max(lo, hi),
                abs(hi - lo),
                EVENT_XTOL,
            )
        lam0 = found.get(v0)
        if lam0 is None:
            lam0 = a.lam[ia] if abs(v0 - a.v) <= abs(v0 - b.v) else b.lam[ib]
        return float(v0), complex(lam0)

    def _segment(self, k: int) -> None:
        """Crossings of tracked eigenvalues between samples k-1 and k."""
        (a, ia), (b, ib) = self.path.samples[k - 1], self.path.samples[k]
        labels = self.path.labels
        ca, cb = _unstable_count(a), _unstable_count(b)
        crossings = []
        # The eigenvalues unstable at one end only (_state_sign > 0, vectorized).
        la_all, lb_all = a.lam[ia], b.lam[ib]
        ua = la_all.real > STABILITY_TOL * np.maximum(1.0, np.abs(la_all))
        ub = lb_all.real > STABILITY_TOL * np.maximum(1.0, np.abs(lb_all))
        for j in np.flatnonzero(ua != ub):
            la, lb = a.lam[ia[j]], b.lam[ib[j]]
            real_a = abs(la.imag) <= IMAG_TOL * max(1.0, abs(la))
            real_b = abs(lb.imag) <= IMAG_TOL * max(1.0, abs(lb))
            if not real_a and not real_b and la.imag < 0 and lb.imag < 0:
                continue  # the lower member of a crossing pair: counted with its partner
            if (a.fold or b.fold) and (real_a or real_b):
                continue  # a real root through zero at a fold: the fold event itself
            if a.v == b.v:
                continue
            v0, lam0 = self._locate(a, b, ia[j], ib[j])
            real = abs(lam0.imag) <= IMAG_TOL * max(1.0, abs(lam0))
            # Unstable on the side of larger v?
            up = (_state_sign(lb) > 0) == (b.v > a.v)
            s0 = a.s + (b.s - a.s) * (v0 - a.v) / (b.v - a.v)
            crossings.append((float(v0), complex(lam0), j, up, real, s0))
        # Whole-system stability on either side of each crossing: the unstable
        # count at the lower-v sample, changed by each crossing in v order (a
        # complex pair counts two, a real root one).
        count = ca if b.v > a.v else cb
        for v0, lam0, j, up, real, s0 in sorted(crossings):
            after = max(0, count + (1 if real else 2) * (1 if up else -1))
            if up:
                typ = "divergence" if real else "flutter"
            else:
                typ = "restabilization" if after == 0 else "mode_restabilization"
            freq = 0.0 if real else float(abs(lam0.imag))
            lam = complex(lam0.real, abs(lam0.imag))
            ev = self._event(v0, typ, freq, labels[j], lam, count == 0, after == 0)
            self.events.append((s0, ev, ca, cb))
            count = after

    def _fold_event(self, k: int) -> None:
        samples = self.path.samples
        f, i_f = samples[k]
        before = _unstable_count(samples[k - 1][0])
        after = _unstable_count(samples[k + 1][0]) if k + 1 < len(samples) else before
        j = int(np.argmin(np.abs(f.lam[i_f])))
        lam = f.lam[i_f][j]
        ev = self._event(f.v, "fold", 0.0, self.path.labels[j], lam, before == 0, after == 0)
        self.events.append((f.s, ev, before, after))

    def _event(self, v, typ, frequency, mode, lam, stable_before, stable_after, **kw):
        """The StabilityEvent of this branch and plane."""
        return StabilityEvent(
            v=float(v),
            type=typ,
            branch=self.name,
            frequency=frequency,
            mode=int(mode),
            eigenvalue=complex(lam),
            stable_before=bool(stable_before),
            stable_after=bool(stable_after),
            plane=self.model.plane,
            **kw,
        )

    def _start_events(self) -> None:
        """Instabilities present at the branch end with the smaller v (listed at that v)."""
        samples = self.path.samples
        first, last = samples[0], samples[-1]
        end, idx = first if first[0].v <= last[0].v else last
        n_u = _unstable_count(end)
        for j, label in enumerate(self.path.labels):
            lam = end.lam[idx[j]]
            if not end.resolved[idx[j]] or _state_sign(lam) <= 0:
                continue
            real = abs(lam.imag) <= IMAG_TOL * max(1.0, abs(lam))
            if not real and lam.imag < 0:
                continue
            typ, freq = ("divergence", 0.0) if real else ("flutter", float(lam.imag))
            ev = self._event(end.v, typ, freq, label, lam, False, False, at_start=True)
            self.events.append((end.s, ev, n_u, n_u))

    # -- results -----------------------------------------------------------
    def first_loss(self) -> StabilityEvent | None:
        """The first event in branch order after which the branch is not stable."""
        start_unstable = _unstable_count(self.path.samples[0][0]) > 0
        for _, ev, before, after in self.events:
            if ev.at_start:
                if start_unstable:
                    return ev
                continue
            if before == 0 and after > 0:
                return ev
        return None

    def refined_bifurcation(self, value: float) -> float:
        """A branch point's v from the real root located through zero by Brent (to 1e-10; the
        continuation's bisection on a determinant stops where the corrector fails, ~7e-8 off).
        """
        near = [
            ev.v
            for _, ev, _, _ in self.events
            if ev.frequency == 0.0 and ev.type != "fold" and abs(ev.v - value) < 1e-5
        ]
        return float(min(near, key=lambda x: abs(x - value))) if near else float(value)

    def finish(self, parent: str | None, born_at: float | None) -> BranchStability:
        samples = [e for e, _ in self.path.samples]
        lo, hi = self.v_lo - 1e-12, self.v_hi + 1e-12
        events = [ev for _, ev, _, _ in self.events if lo <= ev.v <= hi]
        return BranchStability(
            name=self.name,
            parent=parent,
            born_at=born_at,
            v=np.array([e.v for e in samples]),
            theta_tip=np.array([float(self.model.disc.tip @ e.q) for e in samples]),
            max_real=np.array([e.max_real for e in samples]),
            n_unstable=np.array([_unstable_count(e) for e in samples]),
            events=tuple(sorted(events, key=lambda ev: ev.v)),
            folds=tuple(float(f.value) for f in self.branch.folds),
            bifurcations=tuple(self.refined_bifurcation(b.value) for b in self.branch.bifurcations),
            end_reason=self.branch.end_reason,
        )
