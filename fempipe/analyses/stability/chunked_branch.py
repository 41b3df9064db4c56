"""A static branch continued in v piece by piece, and the straight branch without continuation.

:class:`ChunkedBranch` yields :func:`fempipe.analyses.statics.continue_static`'s points as far
as the analysis asks, or on the straight pipe with no branch point (alpha = 0, pi) the same
points without Newton (docs/theory/stability.md, "The straight branch").
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from fempipe.analyses.statics import (
    Branch,
    BranchPoint,
    continue_static,
    solve_sagged,
    solve_static,
)
from fempipe.model.plane.operators import PipeModel

from .linear import straight_is_static, straight_pencil


class ChunkedBranch:
    """A static branch continued in v piece by piece (``chunk`` in v at a time, as far as the
    analysis asks), seen as one branch with renumbered fold and branch-point indices."""

    def __init__(self, branch: Branch | None = None) -> None:
        self.points: list = []
        self.special: list = []
        self.end_reason = "stop"
        self._next = None
        if branch is not None:
            self._add(branch)

    @classmethod
    def follow(
        cls,
        model: PipeModel,
        v_range: tuple[float, float],
        ds_max: float,
        q0: np.ndarray | None,
        max_steps: int,
        chunk: float | None = None,
    ) -> ChunkedBranch:
        lo, hi = v_range
        self = cls()
        kw = {"ds": min(0.05, ds_max), "ds_max": ds_max, "max_steps": max_steps}
        if (q0 is None or not np.any(q0)) and _straight_without_branch_points(model, lo, hi, kw):
            q = np.zeros(model.n)

            def advance(piece_start, tangent):
                v_a = piece_start[0]
                stop = hi if chunk is None else min(hi, v_a + chunk)
                # Spectra every STRAIGHT_STEP * ds_max from the start (the
                # branch-point test above keeps the continuation's own points).
                step = STRAIGHT_STEP * ds_max
                return _straight_piece(model, v_a, stop, step, step, kw["max_steps"])

        else:
            m = model.with_params(replace(model.params, v=lo))
            q = solve_sagged(m).q if q0 is None else solve_static(m, q0=q0).q

            def advance(piece_start, tangent):
                v_a, q_a = piece_start
                stop = hi if chunk is None else min(hi, v_a + chunk)
                ma = model.with_params(replace(model.params, v=v_a))
                return continue_static(ma, "v", stop=stop, q0=q_a, tangent=tangent, **kw)

        self._next = lambda: advance((lo, q), None)
        self._hi, self._advance = hi, advance
        return self

    def _add(self, branch: Branch) -> None:
        skip = 1 if self.points else 0
        offset = len(self.points) - skip
        self.points.extend(branch.points[skip:])
        self.special.extend(replace(s, index=s.index + offset) for s in branch.special)
        self.end_reason = branch.end_reason

    def more(self) -> bool:
        """Continue one more piece; False when the branch is finished."""
        if self._next is None:
            return False
        piece = self._next()
        self._add(piece)
        last = self.points[-1]
        if piece.end_reason != "stop" or last.value >= self._hi:
            self._next = None
        else:
            self._next = lambda: self._advance((last.value, last.q), last.tangent)
        return True

    def is_straight(self) -> bool:
        """Whether every point so far is the straight pipe theta = 0 (exactly)."""
        return bool(self.points) and not any(np.any(p.q) for p in self.points)

    @property
    def folds(self) -> list:
        return [s for s in self.special if s.kind == "fold"]

    @property
    def bifurcations(self) -> list:
        return [s for s in self.special if s.kind == "bifurcation"]

    def iter_points(self):
        """(q, v, is_fold) in arclength order, continuing lazily."""
        i = 0
        while True:
            while i < len(self.points):
                # The folds located in segment [i - 1, i] come before point i.
                for f in self.special:
                    if f.kind == "fold" and f.index == i - 1:
                        yield f.q, f.value, True
                p = self.points[i]
                yield p.q, p.value, False
                i += 1
            if not self.more():
                return


#: Step in v between the spectra of a straight branch, in units of ds_max, from v_min on:
#: 3 to 5 give the events of 1 to 2.5e-11 with half the spectra; beyond, the tracker's
#: halving inserts more than the step saves (docs/theory/stability.md, "The straight branch").
STRAIGHT_STEP = 4.0


def _straight_values(v_a: float, stop: float, ds: float, ds_max: float) -> list[float]:
    """The v ``continue_static`` visits on a straight branch (the same operations, so values)."""
    values, v, h = [v_a], v_a, ds
    while True:
        v = v + h
        if v >= stop:
            values.append(stop)
            return values
        values.append(v)
        h = min(ds_max, h * 1.5)


def _straight_without_branch_points(model: PipeModel, lo: float, hi: float, kw: dict) -> bool:
    """Whether the primary branch over [lo, hi] is the straight pipe with no branch point on it.

    theta = 0 static at every v (alpha = 0, pi), ``hi`` within the step budget, and det K^d of
    the same sign at every point the continuation would visit (the test of
    :meth:`fempipe.solvers.continuation.KellerPolicy.detect` on this branch).
    """
    if not straight_is_static(model.params):
        return False
    values = _straight_values(lo, hi, kw["ds"], kw["ds_max"])
    if len(values) - 1 > kw["max_steps"]:
        return False
    pencil = straight_pencil(model)
    # K^d(v) = K0 + v^2 K2 at every point in one batched LU (the sign of the
    # determinant: product of the pivots' signs and of the row swaps').
    v = np.asarray(values, dtype=float)
    v2 = v * v  # as StraightPencil.matrices forms it
    signs = np.linalg.slogdet(pencil.K0[None, :, :] + v2[:, None, None] * pencil.K2[None])[0]
    return bool(np.all(signs == signs[0]) and signs[0] != 0)


def _straight_piece(
    model: PipeModel, v_a: float, stop: float, ds: float, ds_max: float, max_steps: int
) -> Branch:
    """The straight branch from v_a to stop as ``continue_static`` returns it."""
    n = model.n
    tangent = np.zeros(n + 1)
    tangent[n] = 1.0
    q = np.zeros(n)
    branch = Branch(parameter="v", base=replace(model.params, v=v_a), end_reason="stop")
    values = _straight_values(v_a, stop, ds, ds_max)
    branch.points.extend(BranchPoint(q, float(v), tangent, 0, 0.0, 1) for v in values)
    branch.steps = len(branch.points) - 1
    return branch
