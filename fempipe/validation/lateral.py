"""The motion out of the plane in strong form: an independent check of fempipe.model.out_of_plane.model.

The fourth-order equation of the out-of-plane deflection w(xi, tau) about a planar static
state theta^s (from :func:`fempipe.validation.bvp.solve_static_bvp`), written from that
equation alone, discretized by C^1 spectral elements (:class:`HermiteSpectral`);
:class:`LateralProblem` gives its spectrum along the static branch and
:func:`critical_velocity` the first crossing.  Derivation: docs/theory/independent.md.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.linalg as sla
from numpy.polynomial import legendre as leg

from fempipe.core.parallel import single_blas

from .bvp import BVPSolution, solve_static_bvp
from .classical import Onset, margin_of, scan_onset
from .classical_galerkin import legendre_local_basis, quadratic_eigenvalues

#: Only eigenvalues with |lambda| below this decide stability (the lowest
#: eight modes or so), as in :mod:`fempipe.validation.classical`.
LAM_MAX = 1000.0
#: Relative size of a real part that counts as unstable at v = 0 without damping.
TOL = 1e-9
#: ``solve_bvp`` tolerance of the static states used in the eigenproblems.
BVP_TOL = 1e-10
#: ... and of those of the scan for the first unstable interval (measured at
#: alpha = pi/2, v = 5.66: theta_tip within 5e-12 of the 1e-10 solution).
SCAN_TOL = 1e-8


# The planar static state (independent: solve_bvp on Eq. (31a))


@dataclass(frozen=True)
class StaticState:
    """A planar static state from ``solve_bvp`` (``bvp.sol(xi)``: theta, theta', X_g, Z_g) and the
    spring forces F_s = -kappa_s (r(xi_s) - (xi_s, 0)).
    """

    params: object
    bvp: BVPSolution = field(repr=False)
    spring_forces: tuple = ()

    @property
    def theta_tip(self) -> float:
        return self.bvp.theta_tip

    def theta(self, xi) -> np.ndarray:
        """theta^s at ``xi``."""
        return np.asarray(self.bvp.sol(np.asarray(xi, dtype=float))[0])

    def dtheta(self, xi) -> np.ndarray:
        """theta^s' at ``xi``."""
        return np.asarray(self.bvp.sol(np.asarray(xi, dtype=float))[1])

    def axial_force(self, xi) -> np.ndarray:
        """N(xi) (docs/theory/independent.md); ``xi`` must not be a spring's position."""
        p = self.params
        xi = np.asarray(xi, dtype=float)
        th = self.theta(xi)
        N = p.gamma * (1.0 - xi + p.end_mass) * np.cos(th + p.alpha)
        # 1 - cos(a) = 2 sin^2(a/2): no cancellation on a nearly straight pipe.
        N = N + p.v**2 * 2.0 * np.sin(0.5 * (self.theta_tip - th)) ** 2
        for (_, xs), F in zip(p.springs, self.spring_forces, strict=True):
            N = N + np.where(xi < xs, F[0] * np.cos(th) + F[1] * np.sin(th), 0.0)
        return N

    def eta(self, xi) -> np.ndarray:
        """The in-plane deflection eta^s = \\int_0^xi sin theta^s (rotated back from X_g, Z_g)."""
        y = self.bvp.sol(np.asarray(xi, dtype=float))
        a = self.params.alpha
        return -math.sin(a) * y[2] + math.cos(a) * y[3]


def static_state(params, guess=None, tol: float = BVP_TOL) -> StaticState:
    """The static state of Eq. (31a) at ``params.v`` by ``solve_bvp``; ``guess`` (a state or
    ``guess(xi) -> theta``) selects the branch.
    """
    if isinstance(guess, StaticState):
        guess = guess.theta
    sol = solve_static_bvp(
        params.alpha,
        params.gamma,
        params.v,
        guess=guess,
        tol=tol,
        end_mass=params.end_mass,
        springs=params.springs,
    )
    forces = []
    ca, sa = math.cos(params.alpha), math.sin(params.alpha)
    for kappa, xs in params.springs:
        _, _, X, Z = sol.sol(np.array([xs]))[:, 0]
        r = np.array([ca * X + sa * Z - xs, -sa * X + ca * Z])  # r(xi_s) - (xi_s, 0)
        forces.append(-kappa * r)
    return StaticState(params, sol, tuple(forces))


def loaded_state(params, steps: int = 4, tol: float = BVP_TOL) -> StaticState:
    """The state reached as gravity is switched on, gamma from 0 in steps (the loaded branch, not a
    near-straight unstable one); redone with twice the steps (up to 64) if the pipe does not turn
    towards the plumb line.
    """
    s = math.sin(params.alpha)
    while True:
        st = None
        for g in np.linspace(0.0, params.gamma, steps + 1)[1:-1]:
            st = static_state(replace(params, gamma=float(g)), guess=st, tol=1e-6)
        st = static_state(params, guess=st, tol=tol)
        if abs(s) < 1e-12 or params.gamma == 0.0 or st.theta_tip * s < 0.0 or steps >= 64:
            return st
        steps *= 2


# C^1 spectral elements in w


@functools.cache
def _reference(p: int, nq: int):
    """Basis values and t-derivatives 0..2 at nq Gauss points, weights, integration matrix."""
    t, w = leg.leggauss(nq)
    basis = legendre_local_basis(p)
    vals = np.array([[b.deriv(k)(t) if k else b(t) for b in basis] for k in range(3)])
    # S f = \int_{-1}^{t_i} f for f given at the Gauss points: its Legendre
    # series (exact discrete transform for degree < nq), integrated exactly.
    V = leg.legvander(t, nq - 1)  # (nq, nq)
    coef = (V * w[:, None]).T * ((2.0 * np.arange(nq) + 1.0) / 2.0)[:, None]  # f -> c
    S = np.stack(
        [leg.legval(t, leg.legint(np.eye(nq)[k], lbnd=-1.0)) for k in range(nq)], axis=1
    )  # (nq points, nq coefficients)
    return t, w, vals.transpose(0, 2, 1), S @ coef


class HermiteSpectral:
    """C^1 spectral elements: degree ``p`` + 2 on each of ``elements`` (plus a node at every
    spring), ``extra_points`` more Gauss points per element.
    """

    name = "Hermite-Legendre spectral elements"

    def __init__(self, p: int = 24, elements: int = 1, extra_points: int = 40) -> None:
        self.p, self.elements, self.nq = int(p), int(elements), int(p) + int(extra_points)
        if self.p < 2 or self.elements < 1:
            raise ValueError(f"need p >= 2 and elements >= 1, got p={p}, elements={elements}")

    def label(self) -> str:
        return f"spectral elements p = {self.p}" + (
            f" x {self.elements}" if self.elements > 1 else ""
        )

    def layout(self, params):
        """Nodes, and at the quadrature points: xi, weights, element, basis values and derivatives."""
        nodes = np.unique(
            np.r_[np.linspace(0.0, 1.0, self.elements + 1), [x for _, x in params.springs]]
        )
        S = nodes.size - 1
        nb = self.p - 1
        ndof = 2 * S + S * nb
        t, w, vals, _ = _reference(self.p, self.nq)
        xs, ws, U = [], [], [np.zeros((S * self.nq, ndof)) for _ in range(3)]
        for e in range(S):
            a, b = nodes[e], nodes[e + 1]
            h = b - a
            xs.append(a + h * (t + 1.0) / 2.0)
            ws.append(w * h / 2.0)
            scale = np.ones(4 + nb)
            scale[[1, 3]] = h / 2.0  # Hermite slope functions: d/dxi = 1 at the node
            left = [2 * (e - 1), 2 * (e - 1) + 1] if e > 0 else [-1, -1]
            idx = np.array(left + [2 * e, 2 * e + 1] + list(2 * S + e * nb + np.arange(nb)))
            keep = idx >= 0  # node 0 is clamped: w = w' = 0
            rows = slice(e * self.nq, (e + 1) * self.nq)
            for k in range(3):
                U[k][rows, idx[keep]] = (vals[k] * scale * (2.0 / h) ** k)[:, keep]
        return nodes, np.concatenate(xs), np.concatenate(ws), U

    def cumulative(self, nodes: np.ndarray, f: np.ndarray) -> np.ndarray:
        """``\\int_0^xi f`` at the quadrature points, for f (n_points, ...) given there."""
        _, w, _, Sint = _reference(self.p, self.nq)
        out = np.empty_like(f)
        offset = np.zeros(f.shape[1:])
        for e in range(nodes.size - 1):
            h = nodes[e + 1] - nodes[e]
            fe = f[e * self.nq : (e + 1) * self.nq]
            out[e * self.nq : (e + 1) * self.nq] = offset + 0.5 * h * (Sint @ fe)
            offset = offset + 0.5 * h * np.tensordot(w, fe, axes=(0, 0))
        return out

    def project(self, params, f) -> np.ndarray:
        """The coefficients of the L2 projection of ``f(xi)`` (with f(0) = f'(0) = 0 in mind)."""
        _, x, wq, (U0, _, _) = self.layout(params)
        return np.linalg.solve((U0 * wq[:, None]).T @ U0, U0.T @ (wq * f(x)))

    def values(self, params, a: np.ndarray, xi) -> np.ndarray:
        """w(xi) of the coefficients ``a`` (xi inside the elements, or at their ends)."""
        nodes, _, _, _ = self.layout(params)
        xi = np.atleast_1d(np.asarray(xi, dtype=float))
        basis = legendre_local_basis(self.p)
        S, nb = nodes.size - 1, self.p - 1
        out = np.zeros(xi.shape, dtype=np.result_type(a, float))
        for i, x in enumerate(xi):
            e = min(int(np.searchsorted(nodes, x, side="right")) - 1, S - 1)
            h = nodes[e + 1] - nodes[e]
            t = 2.0 * (x - nodes[e]) / h - 1.0
            loc = np.array([b(t) for b in basis])
            loc[[1, 3]] *= h / 2.0
            idx = [2 * (e - 1), 2 * (e - 1) + 1] if e > 0 else [-1, -1]
            idx = np.array(idx + [2 * e, 2 * e + 1] + list(2 * S + e * nb + np.arange(nb)))
            keep = idx >= 0
            out[i] = loc[keep] @ a[idx[keep]]
        return out

    def matrices(self, state: StaticState):
        """K, C, M about ``state`` at its v and ``parts``: ``bending``, ``material``, ``U0``, ``x``, ``w``."""
        p = state.params
        nodes, x, wq, (U0, U1, U2) = self.layout(p)
        S = nodes.size - 1
        tip = np.zeros(U0.shape[1])
        tip[2 * (S - 1)] = 1.0  # w(1)
        dtip = np.zeros(U0.shape[1])
        dtip[2 * (S - 1) + 1] = 1.0  # w'(1)
        dth = state.dtheta(x)

        def gram(A, B, weight=1.0):
            return (A * (wq * weight)[:, None]).T @ B

        bending = gram(U2, U2)
        slope = gram(U1, U1)
        K = bending + gram(U1, U1, state.axial_force(x) - dth**2)
        K += p.v**2 * (np.outer(tip, dtip) - slope)
        for kappa, xs in p.springs:
            e = np.zeros(U0.shape[1])
            e[2 * (int(np.searchsorted(nodes, xs)) - 1)] = 1.0  # w(xi_s): a node
            K += kappa * np.outer(e, e)
        mass = gram(U0, U0)
        M = mass + p.end_mass * np.outer(tip, tip)
        # B w = w'' + theta' \int_0^xi theta' w': the co-rotational curvature.
        Bw = U2 + dth[:, None] * self.cumulative(nodes, dth[:, None] * U1)
        material = gram(Bw, Bw)
        C = p.external_damping * mass + 2.0 * math.sqrt(p.beta) * p.v * gram(U0, U1)
        C = C + p.mu * material
        parts = {"bending": bending, "material": material, "U0": U0, "x": x, "w": wq}
        return K, C, M, parts


# The quadratic eigenproblem


def eigen(K, C, M, bending=None, vectors: bool = False):
    """Eigenvalues (and vectors) of (K + lambda C + lambda^2 M) a = 0, in the M-orthonormal modes
    of ``bending``, by the shifted reversed companion (as classical.py).
    """
    Kb = 0.5 * (K + K.T) + M if bending is None else bending
    d = 1.0 / np.sqrt(np.diag(M))
    _, Q = sla.eigh(Kb * np.outer(d, d), M * np.outer(d, d))
    Q = d[:, None] * Q
    Kq, Cq, Mq = (Q.T @ A @ Q for A in (K, C, M))
    if not vectors:
        return quadratic_eigenvalues(Kq, Cq, Mq)
    lam, Z = quadratic_eigenvalues(Kq, Cq, Mq, vectors=True)
    return lam, Q @ Z


class LateralProblem:
    """A pipe (hysteretic damping not modelled) on ``disc``, its static branch followed in v from
    ``start`` (default :func:`loaded_state`).
    """

    def __init__(self, params, disc: HermiteSpectral, start: StaticState | None = None) -> None:
        if params.hysteretic_damping:
            raise ValueError("the strong-form check does not model hysteretic damping")
        self.params, self.disc = params, disc
        self._states: dict[float, StaticState] = {}
        self._tols: dict[float, float] = {}
        if start is not None:
            self._states[float(start.params.v)] = start
            self._tols[float(start.params.v)] = 0.0

    def state(self, v: float, tol: float = BVP_TOL) -> StaticState:
        """The static state at ``v``, from the nearest cached one (reused if solved to ``tol``)."""
        v = float(v)
        if v in self._states and self._tols.get(v, 0.0) <= tol:
            return self._states[v]
        p = replace(self.params, v=v)
        if not self._states:
            st = loaded_state(p, tol=tol)
        else:
            near = min(self._states, key=lambda u: abs(u - v))
            st = static_state(p, guess=self._states[near], tol=tol)
        self._states[v], self._tols[v] = st, tol
        return st

    def matrices(self, v: float, tol: float = BVP_TOL):
        """K, C, M and the parts of :meth:`HermiteSpectral.matrices` at ``v``."""
        return self.disc.matrices(self.state(v, tol))

    def eigenvalues(self, v: float, vectors: bool = False, tol: float = BVP_TOL):
        """The eigenvalues (and vectors) at ``v``, static state to ``tol``."""
        K, C, M, parts = self.matrices(v, tol)
        return eigen(K, C, M, bending=parts["bending"], vectors=vectors)


@single_blas
def critical_velocity(
    params,
    v_max: float = 20.0,
    v_min: float = 0.0,
    disc: HermiteSpectral | None = None,
    step: float = 0.25,
    xtol: float = 1e-12,
    lam_max: float = LAM_MAX,
    tol: float = TOL,
    start: StaticState | None = None,
) -> Onset:
    """The first v in [v_min, v_max] where the motion out of the plane is unstable: the first
    ``step`` whose margin turns positive, then Brent's method to ``xtol`` on max Re lambda."""
    disc = HermiteSpectral() if disc is None else disc
    prob = LateralProblem(params, disc, start)

    def margin(v, t=tol, bvp_tol=BVP_TOL):
        return margin_of(prob.eigenvalues(v, tol=bvp_tol), lam_max, t)

    def abscissa(v):
        return margin(v, 0.0)[0]

    def probe(v):
        return margin(v, bvp_tol=SCAN_TOL)[0]

    return scan_onset(margin, abscissa, v_min, v_max, step, xtol, disc.label(), probe)
