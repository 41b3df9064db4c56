"""Pseudo-arclength continuation of static equilibria (Eq. (31a)): folds,
bifurcation points and branch switching at pitchforks.

The engine (:class:`_Continuation`) solves R(q, lambda) = 0 along a curve for
any one-parameter family of models; what the parameter means for the pipe
(v, gamma or alpha, with negative v and gamma mirrored) is said by
:class:`_Family`.  Arclength is measured in the discretisation-independent
norm ``||(theta, lambda)||^2 = \\int_0^1 theta^2 dxi + lambda^2`` (the Gram
matrix of the discretisation), so step sizes mean the same thing on every
mesh.  Folds are sign changes of the parameter component of the tangent;
bifurcation points sign changes of the determinant of the bordered Jacobian,
which keeps its sign at folds.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from fempipe.model.operators import PipeModel
from fempipe.model.params import Params
from fempipe.solvers.newton import DENSE_MAX_N, NewtonError, _balance, _solve, solve_static

__all__ = [
    "BranchPoint",
    "Branch",
    "SpecialPoint",
    "continuation",
    "switch_branch",
    "CONTINUATION_PARAMETERS",
]

#: The parameters a branch can be continued in.
CONTINUATION_PARAMETERS = ("v", "gamma", "alpha")


@dataclass(frozen=True)
class BranchPoint:
    """One point of a continuation branch."""

    q: np.ndarray
    value: float
    tangent: np.ndarray  # unit tangent (dq, dlambda) in the arclength norm
    iterations: int
    residual_norm: float
    det_sign: int  # sign of det of the bordered Jacobian; flips at bifurcations


@dataclass(frozen=True)
class SpecialPoint:
    """A fold or a branch point located on a branch.

    ``kind`` is ``"fold"`` (the parameter turns back: a saddle-node of the
    static problem) or ``"bifurcation"`` (a branch crosses; a pitchfork in the
    symmetric cases alpha = 0, pi).
    """

    kind: str
    value: float
    q: np.ndarray
    tangent: np.ndarray
    index: int  # the branch segment [index, index + 1] that contains it

    def to_dict(self, parameter: str) -> dict:
        return {"type": self.kind, parameter: self.value}


@dataclass
class Branch:
    """A branch of static solutions traced in ``parameter``.

    Attributes
    ----------
    parameter : str
        ``"v"``, ``"gamma"`` or ``"alpha"``.
    points : list of BranchPoint
    special : list of SpecialPoint
        Folds and bifurcation points, located to ``locate_tol`` in arclength.
    steps, rejected_steps : int
        Continuation diagnostics.
    end_reason : str
        ``"stop"`` (reached the requested value), ``"returned to v = 0"``
        (the branch folded back out of the physical range) or ``"max_steps"``.
    """

    parameter: str
    base: Params
    points: list[BranchPoint] = field(default_factory=list)
    special: list[SpecialPoint] = field(default_factory=list)
    steps: int = 0
    rejected_steps: int = 0
    end_reason: str = "max_steps"

    @property
    def values(self) -> np.ndarray:
        return np.array([p.value for p in self.points])

    @property
    def states(self) -> np.ndarray:
        return np.array([p.q for p in self.points])

    @property
    def folds(self) -> list[SpecialPoint]:
        return [s for s in self.special if s.kind == "fold"]

    @property
    def bifurcations(self) -> list[SpecialPoint]:
        return [s for s in self.special if s.kind == "bifurcation"]

    def params_at(self, value: float) -> Params:
        return replace(self.base, **{self.parameter: value})


class _Family:
    """The pipe models along one parameter: the physics a continuation walks through.

    The arclength engine (:class:`_Continuation`) asks only for the model at a
    parameter value and for dR/dlambda; what a value means for the pipe is
    said here.  v and gamma are physical only when >= 0, but a branch may pass
    through 0 (a buckled branch at alpha = pi returns to v = 0), so the
    corrector may ask for negative values.  They are mapped to their mirror
    images: R depends on v only through v^2, and gamma < 0 is |gamma| with
    alpha + pi.  dR/dlambda carries the sign of the map.
    """

    def __init__(self, model: PipeModel, parameter: str) -> None:
        if parameter not in CONTINUATION_PARAMETERS:
            raise ValueError(
                f"continuation parameter must be one of {CONTINUATION_PARAMETERS}, got {parameter!r}"
            )
        self.model = model
        self.parameter = parameter

    def at(self, value: float) -> PipeModel:
        """The model at parameter ``value`` (negative v, gamma mirrored)."""
        p = self.model.params
        if self.parameter == "v":
            p = replace(p, v=abs(value))
        elif self.parameter == "gamma":
            p = replace(p, gamma=abs(value), alpha=p.alpha + (np.pi if value < 0 else 0.0))
        else:
            p = replace(p, alpha=value)
        return self.model.with_params(p)

    def dR_dlambda(self, q: np.ndarray, value: float) -> np.ndarray:
        d = self.at(value).static_parameter_derivative(q, self.parameter)
        return -d if (value < 0 and self.parameter != "alpha") else d


class _Continuation:
    """Pseudo-arclength machinery for R(q, lambda) = 0 on any one-parameter family.

    ``family.at(lambda)`` gives an object with ``static_residual``,
    ``static_jacobian`` and ``static_terms`` (a :class:`PipeModel`);
    ``family.dR_dlambda(q, lambda)`` the parameter derivative.  Arclength is
    measured with the L2 Gram matrix of theta, ``metric``.
    """

    def __init__(self, family: _Family, metric, n: int) -> None:
        self.at = family.at
        self.dR_dlambda = family.dR_dlambda
        # Dense algebra up to DENSE_MAX_N unknowns (fempipe.solvers.newton).
        self.sparse = sp.issparse(metric) and n > DENSE_MAX_N
        self.G = metric.toarray() if sp.issparse(metric) and not self.sparse else metric
        self.n = n

    def dot(self, a: np.ndarray, b: np.ndarray) -> float:
        n = self.n
        return float(a[:n] @ (self.G @ b[:n]) + a[n] * b[n])

    def normalize(self, t: np.ndarray) -> np.ndarray:
        return t / np.sqrt(self.dot(t, t))

    def bordered(self, q: np.ndarray, value: float, t: np.ndarray):
        """[[dR/dq, dR/dlambda], [G t_q, t_lambda]]: the pseudo-arclength Jacobian."""
        m = self.at(value)
        J = m.static_jacobian(q, dense=True) if not self.sparse else m.static_jacobian(q)
        Rl = self.dR_dlambda(q, value)
        n = self.n
        row = np.append(self.G @ t[:n], t[n])
        if self.sparse:
            A = sp.vstack([sp.hstack([J, sp.csc_matrix(Rl[:, None])]), sp.csr_matrix(row[None, :])])
            return A.tocsc()
        return np.block([[J, Rl[:, None]], [row[None, :]]])

    def tangent(self, q: np.ndarray, value: float, t_prev: np.ndarray) -> tuple[np.ndarray, int]:
        """Unit tangent oriented along t_prev, and the sign of det(bordered)."""
        t, sign, _ = self.tangent_det(q, value, t_prev)
        return t, sign

    def tangent_det(
        self, q: np.ndarray, value: float, t_prev: np.ndarray
    ) -> tuple[np.ndarray, int, float]:
        """:meth:`tangent` and log|det(bordered)| (bordered with the row of t_prev)."""
        A = self.bordered(q, value, t_prev)
        rhs = np.zeros(self.n + 1)
        rhs[-1] = 1.0
        t, sign, logdet = _solve_with_det(A, rhs)
        t = self.normalize(t)
        if self.dot(t, t_prev) < 0:
            t = -t
        return t, sign, logdet

    def correct(
        self, y_pred: np.ndarray, t: np.ndarray, tol: float, max_iter: int = 12
    ) -> tuple[np.ndarray, int, float] | None:
        """Newton on [R(q, lambda); <t, y - y_pred>] = 0 from y_pred."""
        n = self.n
        y = y_pred.copy()
        for it in range(1, max_iter + 1):
            m = self.at(y[n])
            r = m.static_residual(y[:n])
            g = np.append(r, self.dot(t, y - y_pred))
            A = self.bordered(y[:n], y[n], t)
            dy = _solve(A, -g)
            if not np.all(np.isfinite(dy)):
                return None
            y = y + dy
            step = np.sqrt(abs(self.dot(dy, dy)))
            if step < 1e-10 * (1.0 + np.sqrt(self.dot(y, y))):
                _, rn, scale = _balance(self.at(y[n]), y[:n])
                if rn <= tol * scale:
                    return y, it, rn
            if step > 1e3:
                return None
        return None


def _pipe_continuation(model: PipeModel, parameter: str) -> _Continuation:
    """The arclength engine on the pipe models along ``parameter`` (:class:`_Family`)."""
    return _Continuation(_Family(model, parameter), model.disc.gram, model.n)


def _perm_sign(perm: np.ndarray) -> int:
    """Sign of a permutation given as an index array, O(n)."""
    perm = np.asarray(perm)
    seen = np.zeros(perm.size, dtype=bool)
    sign = 1
    for i in range(perm.size):
        if not seen[i]:
            j, length = i, 0
            while not seen[j]:
                seen[j] = True
                j = perm[j]
                length += 1
            if length % 2 == 0:
                sign = -sign
    return sign


def _solve_with_sign(A, b: np.ndarray) -> tuple[np.ndarray, int]:
    """Solve A x = b and return sign(det A) from the same LU factorisation."""
    x, sign, _ = _solve_with_det(A, b)
    return x, sign


def _solve_with_det(A, b: np.ndarray) -> tuple[np.ndarray, int, float]:
    """Solve A x = b; sign(det A) and log|det A| from the same LU factorisation."""
    if sp.issparse(A):
        lu = spla.splu(A.tocsc())
        d = lu.U.diagonal()  # SuperLU's L has a unit diagonal
        sign = int(np.prod(np.sign(d))) * _perm_sign(lu.perm_r) * _perm_sign(lu.perm_c)
        x = lu.solve(b)
    else:
        lu, piv = sla.lu_factor(A)
        d = np.diag(lu)
        swaps = int(np.count_nonzero(piv != np.arange(piv.size)))
        sign = int(np.prod(np.sign(d))) * (-1 if swaps % 2 else 1)
        x = sla.lu_solve((lu, piv), b)
    with np.errstate(divide="ignore"):
        logdet = float(np.sum(np.log(np.abs(d))))
    return x, sign, logdet


def continuation(
    model: PipeModel,
    parameter: str = "v",
    stop: float = 10.0,
    q0: np.ndarray | None = None,
    ds: float = 0.1,
    ds_min: float = 1e-6,
    ds_max: float = 0.5,
    max_steps: int = 2000,
    tol: float = 1e-10,
    direction: int | None = None,
    detect: bool = True,
    locate_tol: float = 1e-10,
    tangent: np.ndarray | None = None,
    callback: Callable[[BranchPoint], None] | None = None,
) -> Branch:
    """Pseudo-arclength continuation of static states in ``parameter``.

    Starts at ``model.params`` (Newton from ``q0``), walks with adaptive
    arclength steps until the parameter passes ``stop`` (the last point is
    corrected to lie exactly at ``stop``) or ``max_steps`` is reached.  Folds
    (the parameter turns back) and bifurcation points (sign change of the
    determinant of the bordered Jacobian, which does not change at folds) are
    detected and located by bisection in arclength.

    Parameters
    ----------
    model : PipeModel
    parameter : {'v', 'gamma', 'alpha'}
    stop : float
        Target parameter value (may be below the start value).
    q0 : ndarray, optional
        Initial guess for the first point.
    ds, ds_min, ds_max : float
        Initial, minimal and maximal arclength steps.
    direction : {+1, -1}, optional
        Initial direction in the parameter (default: towards ``stop``).
    tangent : ndarray, shape (n + 1,), optional
        Initial tangent (for branch switching); overrides ``direction``.
    callback : callable, optional
        Called with each accepted :class:`BranchPoint` (progress).

    Returns
    -------
    Branch

    Raises
    ------
    NewtonError
        If the first point does not converge, or the step size falls below
        ``ds_min`` (with the parameter value reached).
    """
    cont = _pipe_continuation(model, parameter)
    n = model.n
    start_value = float(getattr(model.params, parameter))
    if parameter in ("v", "gamma") and stop < 0:
        raise ValueError(f"stop must be >= 0 for {parameter}, got {stop}")
    first = solve_static(model, q0=q0, tol=tol)
    if tangent is None:
        sgn = direction if direction is not None else (1 if stop >= start_value else -1)
        t0 = np.zeros(n + 1)
        t0[n] = float(sgn)
    else:
        t0 = cont.normalize(np.asarray(tangent, dtype=float))
    t, sign = cont.tangent(first.q, start_value, t0)
    branch = Branch(parameter=parameter, base=model.params)
    pt = BranchPoint(first.q, start_value, t, first.iterations, first.residual_norm, sign)
    branch.points.append(pt)
    if callback:
        callback(pt)
    h = ds
    going_up = stop >= start_value
    for _ in range(max_steps):
        prev = branch.points[-1]
        y_prev = np.append(prev.q, prev.value)
        res = cont.correct(y_prev + h * prev.tangent, prev.tangent, tol)
        if res is None:
            branch.rejected_steps += 1
            h *= 0.5
            if h < ds_min:
                raise NewtonError(
                    f"continuation in {parameter} stalled at {parameter}={prev.value:.8g}: "
                    f"arclength step fell below {ds_min:g}",
                    params=branch.params_at(prev.value),
                    iterations=0,
                    residual=float("nan"),
                )
            continue
        y, its, rn = res
        t_new, sign = cont.tangent(y[:n], y[n], prev.tangent)
        # Refuse steps that turn too sharply: they may jump branches.
        if cont.dot(t_new, prev.tangent) < 0.8 and h > ds_min * 4:
            branch.rejected_steps += 1
            h *= 0.5
            continue
        new = BranchPoint(y[:n], float(y[n]), t_new, its, rn, sign)
        branch.steps += 1
        crossed = (new.value - stop) * (1 if going_up else -1) >= 0
        left = parameter in ("v", "gamma") and new.value < 0 <= prev.value
        if crossed or left:
            # Land exactly on the stop value (or on the end of the physical
            # range, 0) by Newton at fixed parameter.
            target = stop if crossed else 0.0
            end = solve_static(cont.at(target), q0=_interp_state(prev, new, target), tol=tol)
            t_end, s_end = cont.tangent(end.q, target, new.tangent)
            new = BranchPoint(end.q, target, t_end, end.iterations, end.residual_norm, s_end)
            branch.end_reason = "stop" if crossed else f"returned to {parameter} = 0"
            crossed = True
        if detect:
            _detect(cont, branch, prev, new, locate_tol, tol)
        branch.points.append(new)
        if callback:
            callback(new)
        if crossed:
            return branch
        h = min(ds_max, h * (1.5 if its <= 3 else (1.0 if its <= 5 else 0.5)))
    return branch


def _interp_state(a: BranchPoint, b: BranchPoint, value: float) -> np.ndarray:
    if b.value == a.value:
        return b.q
    s = (value - a.value) / (b.value - a.value)
    return a.q + s * (b.q - a.q)


def _detect(
    cont: _Continuation,
    branch: Branch,
    a: BranchPoint,
    b: BranchPoint,
    locate_tol: float,
    tol: float,
) -> None:
    """Locate a fold (t_lambda changes sign) or a bifurcation (det sign flip) in [a, b]."""
    n = cont.n
    idx = len(branch.points) - 1
    if a.tangent[n] * b.tangent[n] < 0:
        sp_ = _bisect(cont, a, b, lambda y, t, s, logdet: t[n], locate_tol, tol)
        if sp_ is not None:
            branch.special.append(SpecialPoint("fold", float(sp_[0][n]), sp_[0][:n], sp_[1], idx))
    if a.det_sign != b.det_sign:
        # At a fold the bordered determinant keeps its sign; a flip is a branch point.
        # The test function is the determinant itself (relative to its value at a,
        # so that it neither overflows nor underflows): continuous and linear
        # through a simple branch point, which the interpolation of _bisect needs.
        _, _, logdet_a = cont.tangent_det(a.q, a.value, a.tangent)
        sp_ = _bisect(
            cont, a, b, lambda y, t, s, logdet: s * np.exp(logdet - logdet_a), locate_tol, tol
        )
        if sp_ is not None:
            # The bordered matrix is singular at a branch point, so the tangent
            # computed there is meaningless; the chord of the bracketing
            # points is the known branch's direction to O(step^2).
            chord = np.append(b.q - a.q, b.value - a.value)
            branch.special.append(
                SpecialPoint(
                    "bifurcation", float(sp_[0][n]), sp_[0][:n], cont.normalize(chord), idx
                )
            )
    branch.special.sort(key=lambda s: (s.index, s.value))


def _bisect(cont: _Continuation, a: BranchPoint, b: BranchPoint, f, locate_tol: float, tol: float):
    """Bisection in arclength along the secant from a, for a sign change of f.

    ``f(y, t, sign, logdet)`` is a test function continuous along the branch
    (t the tangent at y, sign and logdet those of the bordered matrix with the
    row of a's tangent).  The bracket is halved until it is below
    ``locate_tol``.  Near a branch point the bordered matrix is singular and the
    corrector stops converging before that (2.7e-8 from the pitchfork of
    alpha = pi, gamma = 18.9 in v, bracket 3.8e-6): the point is then the zero of
    the linear interpolant of f between the bracket's two corrected ends, the
    state interpolated alike, an error O(w^2) for a bracket of width w (1e-12
    there, instead of the 1.9e-6 of the last corrected point).
    """
    n = cont.n
    ya = np.append(a.q, a.value)
    yb = np.append(b.q, b.value)
    chord = yb - ya
    length = np.sqrt(cont.dot(chord, chord))
    if length == 0:
        return None
    direction = chord / length
    t_ref = a.tangent

    def evaluate(y):
        t, sign, logdet = cont.tangent_det(y[:n], y[n], t_ref)
        return t, f(y, t, sign, logdet)

    # The bracket's ends: (position along the chord, state, tangent, f).
    lo = (0.0, ya, *evaluate(ya))
    hi = (length, yb, *evaluate(yb))
    best = None
    while hi[0] - lo[0] > locate_tol:
        mid = 0.5 * (lo[0] + hi[0])
        res = cont.correct(ya + mid * direction, direction, tol)
        if res is None:
            return _interpolate_zero(cont, lo, hi)
        y = res[0]
        t, fm = evaluate(y)
        best = (y, t)
        if np.sign(fm) == np.sign(lo[3]):
            lo = (mid, y, t, fm)
        else:
            hi = (mid, y, t, fm)
    return best


def _interpolate_zero(cont: _Continuation, lo: tuple, hi: tuple):
    """The zero of f interpolated linearly between the bracket's ends
    ``(s, y, t, f)`` (f of opposite signs): its state and unit tangent."""
    f_lo, f_hi = lo[3], hi[3]
    w = f_lo / (f_lo - f_hi) if f_lo != f_hi else 0.5
    y = lo[1] + w * (hi[1] - lo[1])
    t = cont.normalize(lo[2] + w * (hi[2] - lo[2]))
    return y, t


def switch_branch(
    model: PipeModel,
    point: SpecialPoint,
    parameter: str,
    stop: float,
    ds: float = 0.05,
    **kwargs,
) -> tuple[Branch, Branch]:
    """Follow both branches that cross ``point`` (a located bifurcation).

    The bifurcating direction is the null vector of dR/dq orthogonal (in the
    arclength metric) to the known branch's tangent; each new branch starts one
    step ``ds`` away along ``+/-`` that direction and is then continued towards
    ``stop``.  At the pitchforks of alpha = 0 and alpha = pi these are the two
    mirror-image buckled branches theta and -theta.

    Returns
    -------
    (Branch, Branch)
        The branches leaving along +phi and -phi.
    """
    cont = _pipe_continuation(model, parameter)
    n = model.n
    m = cont.at(point.value)
    J = m.static_jacobian(point.q)
    Jd = J.toarray() if sp.issparse(J) else J
    Rl = cont.dR_dlambda(point.q, point.value)
    # Null space of [J, R_lambda] (dimension 2 at a simple branch point).
    A = np.hstack([Jd, Rl[:, None]])
    _, _, Vt = np.linalg.svd(A)
    N2 = Vt[-2:].T
    # Remove the component along the known tangent, in the arclength metric.
    t0 = point.tangent
    cand = [N2[:, 0], N2[:, 1]]
    cand = [c - cont.dot(c, t0) / cont.dot(t0, t0) * t0 for c in cand]
    phi = max(cand, key=lambda c: cont.dot(c, c))
    phi = cont.normalize(phi)
    out = []
    for sgn in (1.0, -1.0):
        y0 = np.append(point.q, point.value) + sgn * ds * phi
        res = cont.correct(y0, sgn * phi, kwargs.get("tol", 1e-10))
        if res is None:
            raise NewtonError(
                f"branch switching failed at {parameter}={point.value:.8g}",
                params=cont.at(point.value).params,
                iterations=0,
                residual=float("nan"),
            )
        y = res[0]
        start = cont.at(float(y[n]))
        tangent = sgn * phi
        br = continuation(start, parameter, stop=stop, q0=y[:n], tangent=tangent, ds=ds, **kwargs)
        out.append(br)
    return out[0], out[1]
