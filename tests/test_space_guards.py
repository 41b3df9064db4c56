"""The 3-D model's terms against the kinematics alone: each term's virtual power, the gauge.

At random non-planar states (U, U', U'') every term of the weak form
(:mod:`fempipe.model.three_d.model`) is isolated as a difference of residuals in its own
parameter (sigma, mu, v, beta, Gamma, gamma, v_dot, the gauge's weight) and tested
with U' (its power).  The references are computed here from the chart alone
(:func:`fempipe.model.three_d.chart.tangent`, the fields evaluated on a fine uniform
grid of their own): the centerline velocity and acceleration by central differences in
tau along U + tau U' + tau^2 U''/2, the co-rotational curvature rate from a
twist-free (parallel-transported) section frame.  None of the model's term methods,
integration operators or quadrature rule is used, so a wrong sign or factor of a term
breaks its identity.

Tolerances: the references carry the fine grid's error (midpoint and trapezoid rules,
O(h^2) with h = 1/M, M = 20000: about 1e-9 relative) and the central differences'
(five-point, O(h^4)); the model carries its Gauss rule's error for integrands that
are not polynomials (6 points a cell on P3:4).  The measured gaps at the two states
are at most 3.2e-8 relative (Kelvin-Voigt; the others 1e-9 to 9e-9); the limit 1e-6 is
30 times that, and a flipped term moves its power by 200 % (a dropped factor by 50 % or
more).
"""

from __future__ import annotations

import numpy as np
import pytest

from fempipe.model.discretization import FiniteElement
from fempipe.model.out_of_plane.model import build_out_of_plane_model
from fempipe.model.params import Params
from fempipe.model.three_d.chart import _Point, fiber_direction, tangent
from fempipe.model.three_d.dynamics import PipeDynamics3D
from fempipe.model.three_d.model import PipeModel3D

M_FINE = 20000
EPS = 1e-5
RTOL = 1e-6

BASE = dict(alpha=1.1, v=3.0, beta=0.3, gamma=7.0, mu=0.0, end_mass=0.0, external_damping=0.0)


class Kinematics:
    """The centerline of a 3-D state on a fine uniform grid, from the chart alone."""

    def __init__(self, disc: FiniteElement, U, Ud, Udd) -> None:
        self.x = np.linspace(0.0, 1.0, M_FINE + 1)
        self.h = 1.0 / M_FINE
        self.B = disc.basis_values(self.x)
        self.n = disc.n
        self.U, self.Ud, self.Udd = (np.asarray(a, float) for a in (U, Ud, Udd))

    def fields(self, s: float) -> np.ndarray:
        """u = (theta, a, b) at tau = s along U + s U' + s^2 U''/2, shape (M + 1, 3)."""
        V = self.U + s * self.Ud + 0.5 * s * s * self.Udd
        return np.stack([self.B @ V[k * self.n : (k + 1) * self.n] for k in range(3)], axis=1)

    def tangent(self, s: float = 0.0) -> np.ndarray:
        return np.asarray(tangent(self.fields(s)[:, :, None]))[:, :, 0]

    def position(self, s: float = 0.0) -> np.ndarray:
        """r(xi) = \\int_0^xi t, cumulative trapezoid rule."""
        t = self.tangent(s)
        r = np.zeros_like(t)
        r[1:] = np.cumsum(0.5 * self.h * (t[1:] + t[:-1]), axis=0)
        return r

    def rates(self, f):
        """(f, f_dot, f_ddot) at tau = 0 of a function of s, by five-point central
        differences (step 2e-3: truncation O(h^4) ~ 1e-11, round-off of the cumulative
        sums ~ 1e-13 / h^2 ~ 1e-8)."""
        h = 2e-3
        f2, f1, f0, g1, g2 = (f(s * h) for s in (2, 1, 0, -1, -2))
        return (f0, (-f2 + 8 * f1 - 8 * g1 + g2) / (12 * h),
                (-f2 + 16 * f1 - 30 * f0 + 16 * g1 - g2) / (12 * h * h))  # fmt: skip

    def integral(self, f: np.ndarray) -> float:
        """\\int_0^1 f by the trapezoid rule on the grid."""
        return float(self.h * (f.sum(axis=0) - 0.5 * (f[0] + f[-1])))

    def curvature(self, s: float) -> np.ndarray:
        """(kappa . d_1, kappa . d_2) at the cell midpoints, in the twist-free frame.

        The section frame (d_1, d_2) starts as (e_2, e_3) at the clamp and is carried
        along the centerline by the least rotation taking t_j to t_{j+1}: no spin about
        the tangent (zero twist).  kappa = t x t' is the rotation's axis times its angle
        over the grid step.
        """
        t = self.tangent(s)
        axis = np.cross(t[:-1], t[1:])
        sin_a = np.linalg.norm(axis, axis=1)
        angle = np.arctan2(sin_a, np.einsum("ij,ij->i", t[:-1], t[1:]))
        k = axis / np.where(sin_a > 0, sin_a, 1.0)[:, None]
        kappa = k * (angle / self.h)[:, None]
        # Rodrigues: R_j = c I + s [k]_x + (1 - c) k k^T turns t_j to t_{j+1}; it leaves
        # k (and so kappa_j) fixed, so kappa_j's components at the midpoint are those in
        # the frame at t_j.
        c, sn = np.cos(angle)[:, None, None], np.sin(angle)[:, None, None]
        cross = np.zeros((k.shape[0], 3, 3))
        cross[:, 0, 1], cross[:, 0, 2], cross[:, 1, 2] = -k[:, 2], k[:, 1], -k[:, 0]
        cross -= cross.transpose(0, 2, 1)
        R = c * np.eye(3) + sn * cross + (1 - c) * k[:, :, None] * k[:, None, :]
        out = np.empty((k.shape[0], 2))
        d = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])  # rows d_1, d_2
        for j in range(k.shape[0]):
            out[j] = d @ kappa[j]
            d = d @ R[j].T
        return out


def _state(disc, seed: int):
    """A random non-planar state and rates on ``disc`` (smooth fields of random weight)."""
    rng = np.random.default_rng(seed)
    x = disc.quad.x
    P = np.asarray(disc.Phi.toarray() if hasattr(disc.Phi, "toarray") else disc.Phi)

    def field(scale):
        c = rng.normal(size=3) * scale
        f = c[0] * np.sin(np.pi * x / 2) + c[1] * x**2 + c[2] * np.sin(3 * np.pi * x / 2)
        return np.linalg.lstsq(P, f, rcond=None)[0]

    return tuple(np.concatenate([field(s) for s in scales]) for scales in
                 ((0.8, 0.3, 0.3), (0.6, 0.4, 0.4), (2.0, 1.0, 1.0)))  # fmt: skip


DISC = FiniteElement(4, 3)


def _residual(U, Ud, Udd, v_dot=0.0, weight=None, **params):
    model = PipeModel3D(DISC, Params(**{**BASE, **params}))
    if weight is not None:
        model.gauge_weight = weight
    return model.residual(U, Ud, Udd, v_dot)


def _powers(seed: int) -> dict:
    """{term: (power from the residual, power from the kinematics)}."""
    U, Ud, Udd = _state(DISC, seed)
    kin = Kinematics(DISC, U, Ud, Udd)
    Z = np.zeros_like(U)
    p = BASE
    t = kin.tangent()
    r, rd, rdd = kin.rates(kin.position)
    tip_d, tip_dd = rd[-1], rdd[-1]
    g = np.array([np.cos(p["alpha"]), -np.sin(p["alpha"]), 0.0])
    out = {}

    def term(**changes):  # U' . (R with the term - R without it), at (U, U', 0)
        on = {k: v[0] for k, v in changes.items()}
        off = {k: v[1] for k, v in changes.items()}
        return float(Ud @ (_residual(U, Ud, Z, **on) - _residual(U, Ud, Z, **off)))

    sigma, mu, G, vd = 0.4, 0.07, 0.3, 1.7
    out["external_damping"] = (
        term(external_damping=(sigma, 0.0)),
        sigma * kin.integral(np.einsum("qc,qc->q", rd, rd)),
    )
    k_dot = (kin.curvature(EPS) - kin.curvature(-EPS)) / (2 * EPS)
    out["kelvin_voigt"] = (term(mu=(mu, 0.0)), mu * kin.h * float(np.sum(k_dot**2)))
    # R is a v + b v^2 in v (Coriolis, follower): separate them from v, 2 v and 0.
    v = p["v"]
    R0, R1, R2 = (float(Ud @ _residual(U, Ud, Z, v=s * v)) for s in (0.0, 1.0, 2.0))
    out["coriolis"] = (0.5 * (4 * R1 - R2 - 3 * R0), v * np.sqrt(p["beta"]) * tip_d @ tip_d)
    out["follower"] = (0.5 * (R2 - 2 * R1 + R0), v * v * tip_d @ t[-1])
    out["flow_acceleration"] = (
        float(Ud @ (_residual(U, Ud, Z, v_dot=vd) - _residual(U, Ud, Z))),
        vd * np.sqrt(p["beta"]) * kin.integral(np.einsum("qc,qc->q", t, rd)),
    )
    out["gravity"] = (
        float(Ud @ (_residual(U, Z, Z) - _residual(U, Z, Z, gamma=0.0))),
        -p["gamma"] * kin.integral(rd @ g),
    )
    # The end mass alone (gamma = 0: no weight): its inertia, Gamma r_ddot(1) . r_dot(1).
    out["end_mass_inertia"] = (
        float(
            Ud @ (_residual(U, Ud, Udd, gamma=0.0, end_mass=G) - _residual(U, Ud, Udd, gamma=0.0))
        ),  # fmt: skip
        G * tip_dd @ tip_d,
    )
    # The pipe's inertia and bending: the whole residual at v = 0 without weight, damping
    # or gauge is d/dtau of T + V_bending, T = (1/2) \int |r_dot|^2.
    t0, td, _ = kin.rates(kin.tangent)
    dx = np.diff(t0, axis=0) / kin.h  # t' at the midpoints
    dxd = np.diff(td, axis=0) / kin.h
    out["inertia and bending"] = (
        float(Ud @ _residual(U, Ud, Udd, v=0.0, gamma=0.0, weight=0.0)),
        kin.integral(np.einsum("qc,qc->q", rd, rdd)) + kin.h * float(np.sum(dx * dxd)),
    )
    return out


TERMS = ("external_damping", "kelvin_voigt", "coriolis", "follower", "flow_acceleration",
         "gravity", "end_mass_inertia", "inertia and bending")  # fmt: skip


@pytest.fixture(scope="module")
def powers():
    return [_powers(seed) for seed in (3, 11)]


@pytest.mark.parametrize("term", TERMS)
def test_power_of_each_term_from_the_kinematics(powers, term):
    """Each term's virtual power for the test U' equals the power its force does, computed
    from the centerline alone: sigma \\int |r_dot|^2, mu \\int |k|^2 (k the rate of the
    curvature in the twist-free frame), v sqrt(beta) |r_dot(1)|^2, v^2 r_dot(1) . t(1),
    v_dot sqrt(beta) \\int t . r_dot, -gamma \\int r_dot . g, Gamma r_ddot(1) . r_dot(1),
    and d/dtau of (1/2) \\int |r_dot|^2 + (1/2) \\int |t'|^2."""
    for case in powers:
        got, ref = case[term]
        assert abs(ref) > 1e-3, (term, ref)  # the state exercises the term
        assert got == pytest.approx(ref, rel=RTOL), (term, got, ref, got / ref - 1)


def test_kelvin_voigt_dissipates():
    """mu \\int |k|^2 >= 0 at every state: the objective damping never feeds the pipe."""
    for seed in range(5):
        U, Ud, _ = _state(DISC, seed)
        Z = np.zeros_like(U)
        assert Ud @ (_residual(U, Ud, Z, mu=0.05) - _residual(U, Ud, Z)) > 0


def test_gauge_term_is_its_equation():
    """The gauge's part of the residual (its weight w_g times the rest) equals
    ``\\int phi_i w_g r_g f_c``, with r_g = d/dtau (f . u_dot) + c_g f . u_dot + k_g f . (0, a, b)
    computed here from the chart's fiber by central differences in tau, on a Gauss rule
    of its own (8 points a cell; the model has 6)."""
    U, Ud, Udd = _state(DISC, 5)
    model = PipeModel3D(DISC, Params(**BASE))
    w_g = model.gauge_weight
    got = _residual(U, Ud, Udd) - _residual(U, Ud, Udd, weight=0.0)

    xg, wg = np.polynomial.legendre.leggauss(8)
    edges = np.linspace(0.0, 1.0, 5)
    x = (0.5 * (edges[:-1, None] + edges[1:, None]) + 0.5 * np.diff(edges)[:, None] * xg).ravel()
    w = (0.5 * np.diff(edges)[:, None] * wg).ravel()
    B = DISC.basis_values(x).toarray()
    n = DISC.n

    def at(V):
        return np.stack([B @ V[k * n : (k + 1) * n] for k in range(3)], axis=1)

    def fiber_rate(s):
        u = at(U + s * Ud + 0.5 * s * s * Udd)
        f = np.asarray(fiber_direction(_Point.of(u[:, :, None])))[:, :, 0]
        return f, np.einsum("qc,qc->q", f, at(Ud + s * Udd))

    (_, rp), (f0, r0), (_, rm) = fiber_rate(EPS), fiber_rate(0.0), fiber_rate(-EPS)
    u = at(U)
    r_g = ((rp - rm) / (2 * EPS) + model.gauge_damping * r0
           + model.gauge_stiffness * np.einsum("qc,qc->q", f0[:, 1:], u[:, 1:]))  # fmt: skip
    ref = np.concatenate([B.T @ (w * w_g * r_g * f0[:, c]) for c in range(3)])
    assert np.abs(ref).max() > 1e-2
    assert np.abs(got - ref).max() < 1e-6 * np.abs(ref).max(), np.abs(got - ref).max()


# ------------------------------------------- linearization about a planar static state --
def _first_order_eigenvalues(K, C, M) -> np.ndarray:
    n = K.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    return np.linalg.eigvals(A)


def _out_of_plane_roots(n_el: int, params: Params, k: int = 6):
    """The k roots of least modulus of the out-of-plane model about the static state, the
    discretization and the state."""
    from fempipe.analyses.statics import solve_static
    from fempipe.model.plane.operators import PipeModel

    disc = FiniteElement(n_el, 3)
    planar = PipeModel(disc, params)
    q = solve_static(planar).q
    lam = _first_order_eigenvalues(*build_out_of_plane_model(planar).linearization(q))
    return lam[np.argsort(np.abs(lam))][:k], disc, q, planar


def _space_block_roots(disc, params, q) -> np.ndarray:
    """The roots of the out-of-plane block (fields a, b) of the 3-D Jacobians about the
    planar state q, without the gauge's (near -50 and -100)."""
    from fempipe.model.three_d.model import planar_state

    n = disc.n
    out = np.r_[n : 3 * n]
    J = PipeModel3D(disc, params).jacobians(planar_state(q))
    lam = _first_order_eigenvalues(*(X[np.ix_(out, out)] for X in J))
    return lam[np.abs(lam + 75.0) > 40.0]


def _gap(lam, ref) -> float:
    return max(float(np.min(np.abs(lam - r)) / abs(r)) for r in ref)


@pytest.mark.parametrize("alpha", [0.6, 2.2])
def test_3d_linearization_with_every_variant_is_the_out_of_plane_model(alpha):
    """Two independent derivations of the motion out of the plane of a static state (the
    3-D weak form linearized, and the out-of-plane model with its axial force, curvature
    softening and objective damping), with an end mass, external damping, flow and
    Kelvin-Voigt damping: their roots agree to a small fraction of the discretization
    error and converge faster than it.

    The scale is the out-of-plane model's own error on P3:N, |roots(N) - roots(2N)|
    (measured 1.4e-3 and 2.9e-5 relative on P3:4 and P3:8 at alpha = 0.6, 1.2e-3 and
    2.5e-5 at 2.2); the two models differ by 6.5e-7, 1.5e-8 (alpha = 0.6) and 1.8e-5,
    2.8e-7 (2.2): at most 1.1e-2 of it, and falling 44-63 times from P3:4 to P3:8.
    A term of either model with a wrong sign or factor leaves a gap that does not fall
    with the mesh."""
    params = Params(alpha=alpha, v=4.0, mu=0.05, end_mass=0.2, external_damping=0.3)
    gaps = {}
    for n_el in (4, 8):
        ref, disc, q, _ = _out_of_plane_roots(n_el, params)
        fine = _out_of_plane_roots(2 * n_el, params)[0]
        error = _gap(fine, ref)
        gaps[n_el] = _gap(_space_block_roots(disc, params, q), ref)
        assert gaps[n_el] < 0.05 * error, (n_el, gaps[n_el], error)
    assert gaps[8] < gaps[4] / 16, gaps  # at least h^4 (measured h^5.5 to h^6)


def test_hanging_pipe_out_of_plane_roots_are_the_in_plane_ones():
    """alpha = 0: the static state is straight, every plane through the vertical alike, so
    the 3-D model's out-of-plane block has the planar model's in-plane roots (the same
    discretization: equal to round-off and eigenvalue conditioning; measured 3.3e-10)."""
    params = Params(alpha=0.0, v=4.0, mu=0.05, end_mass=0.2, external_damping=0.3)
    _, disc, q, planar = _out_of_plane_roots(6, params)
    assert np.abs(q).max() == 0.0
    in_plane = _first_order_eigenvalues(*planar.linearization(q))
    lam = _space_block_roots(disc, params, q)
    assert lam.size == in_plane.size
    assert _gap(lam, in_plane) < 1e-8 and _gap(in_plane, lam) < 1e-8


# --------------------------------------------------------- a conservation law of the motion --
def _angular_momentum(model: PipeModel3D, U, Ud, eps: float = 1e-6) -> float:
    """e_1 . \\int_0^1 r x r_dot: the angular momentum about the vertical through the clamp
    (alpha = 0: gravity along e_1), from the chart's tangents (r_dot by central differences)."""
    t = model.tangents(U)[:, :, 0]
    t_dot = (model.tangents(U + eps * Ud)[:, :, 0] - model.tangents(U - eps * Ud)[:, :, 0]) / (
        2 * eps
    )
    r, r_dot = model.quad.cumulative(t), model.quad.cumulative(t_dot)
    return float(model.w @ np.cross(r, r_dot)[:, 0])


def test_angular_momentum_about_the_vertical_is_conserved():
    """The hanging pipe (alpha = 0) without flow or damping: gravity and the clamp exert no
    moment about the vertical, so e_1 . \\int r x r_dot is constant.  The chart is not
    symmetric under turns about e_1, so the discrete model conserves it only to its
    discretization error, which must fall at a high order.

    A swirling start (bent in the plane, thrown out of it), tau in [0, 0.25], rtol 1e-9:
    measured drifts 5.0e-7, 1.05e-7, 3.8e-8 of L = 0.0834 on P3:2, 3, 4 (orders 3.85 and
    3.5), each far above the integration's ~1e-10."""
    from fempipe.solvers.radau import Radau

    drifts = {}
    for n_el in (2, 3):
        disc = FiniteElement(n_el, 3)
        model = PipeModel3D(disc, Params(alpha=0.0, v=0.0, mu=0.0, gamma=10.0))
        P = disc.Phi.toarray()
        s = np.linalg.lstsq(P, np.sin(np.pi * disc.quad.x / 2), rcond=None)[0]
        zero = np.zeros_like(s)
        U0, Ud0 = np.r_[0.6 * s, zero, zero], np.r_[zero, zero, -0.8 * s]
        L0 = _angular_momentum(model, U0, Ud0)
        stepper = Radau(PipeDynamics3D(model), U0, Ud0, rtol=1e-9)
        drift = max(abs(_angular_momentum(model, q, p) - L0) for _, q, p in stepper.steps(0.25))
        assert np.abs(stepper.q[disc.n :]).max() > 0.05  # the motion left the plane
        drifts[n_el] = drift / abs(L0)
    assert drifts[2] < 2e-5, drifts
    order = np.log(drifts[2] / drifts[3]) / np.log(1.5)
    assert order > 3.0, (drifts, order)


# -------------------------------------------- the weak form on an exact large-amplitude motion --
def test_weak_form_vanishes_on_the_whirl_of_the_rotating_frame_bvp():
    """The whirl of the hanging pipe at v = 7 (tip radius 0.24, every nonlinear term at
    large amplitude), solved as a steady state of the rotating frame by scipy's solve_bvp
    (:mod:`fempipe.validation.whirl_bvp`, no code shared with the weak form), turned rigidly
    at its rate omega and put on P3:N (:func:`fempipe.analyses.three_d.whirl.whirl_state`,
    the rates by five-point differences in tau): the residual of the 3-D weak form without
    its gauge (which the physics does not see) falls with the mesh.

    Measured ||R|| / ||R(U, 0, 0)|| (the static forces the motion balances): 2.8e-3 on
    P3:4, 5.2e-4 on P3:8 (order 2.4; 1.3e-4 on P3:16).  The Kelvin-Voigt term alone is
    1.7e-2 of the scale at every mesh, so a wrong sign of any term leaves a residual that
    does not fall."""
    from test_space_whirl import _flutter_mode

    from fempipe.analyses.three_d.whirl import whirl_state
    from fempipe.validation.whirl_bvp import solve_whirl_bvp

    lam, slope = _flutter_mode()
    whirl = solve_whirl_bvp(7.0, hopf=(6.33, abs(lam.imag)), slope=slope, tol=1e-10)
    assert whirl.radius > 0.2

    def turned(model, tau):
        c, s = np.cos(whirl.omega * tau), np.sin(whirl.omega * tau)
        R = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
        return whirl_state(model, lambda x: R @ whirl.sol(x)[3:6], whirl.omega)[0]

    rel = {}
    for n_el in (4, 8):
        model = PipeModel3D(FiniteElement(n_el, 3), Params(alpha=0.0, v=7.0))
        model.gauge_weight = 0.0
        h = 2e-3
        U2, U1, U0, V1, V2 = (turned(model, k * h) for k in (2, 1, 0, -1, -2))
        Ud = (-U2 + 8 * U1 - 8 * V1 + V2) / (12 * h)
        Udd = (-U2 + 16 * U1 - 30 * U0 + 16 * V1 - V2) / (12 * h * h)
        r = model.residual(U0, Ud, Udd)
        rel[n_el] = np.linalg.norm(r) / np.linalg.norm(model.residual(U0))
    assert rel[8] < 2e-3, rel
    assert np.log2(rel[4] / rel[8]) > 1.5, rel
