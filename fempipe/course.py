"""Check an answer to an exercise of the course (``docs/course/lesson_*.py``).

    >>> from fempipe.course import check
    >>> check("1.3", -0.4166667)
    exercise 1.3: correct (within 1e-05 of the closed form -gamma (1/6 + Gamma/2))
    True

Each reference is computed here by other means than the lesson's exercise asks for: a
closed form, exact rational arithmetic, scipy's ``solve_bvp`` on the strong form of
Eq. (31a) (:mod:`fempipe.validation.bvp`), the classical theory of the straight pipe
(:mod:`fempipe.validation.classical`), the theoretical order of a method, or the other side
of a balance.  A wrong answer is told how far off it is, not what the reference is.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from fractions import Fraction

import numpy as np

__all__ = ["check", "exercises", "reference"]

# key "lesson.exercise" -> (reference, absolute tolerance, what the reference is)
_EXERCISES: dict[str, tuple[Callable[[], float], float, str]] = {}


def _exercise(key: str, tol: float, source: str):
    def register(fn: Callable[[], float]) -> Callable[[], float]:
        _EXERCISES[key] = (functools.cache(fn), tol, source)
        return fn

    return register


def exercises() -> list[str]:
    """The keys of the exercises that :func:`check` knows, ``"1.1"`` to ``"8.3"``."""
    return sorted(_EXERCISES, key=lambda k: tuple(map(int, k.split("."))))


def reference(exercise: str) -> tuple[float, float, str]:
    """(reference value, tolerance, what the reference is) of one exercise."""
    if exercise not in _EXERCISES:
        raise ValueError(f"no exercise {exercise!r}; the exercises are {', '.join(exercises())}")
    fn, tol, source = _EXERCISES[exercise]
    return fn(), tol, source


def check(exercise: str, answer: float) -> bool:
    """Compare ``answer`` with the exercise's independent reference; print and return the verdict."""
    ref, tol, source = reference(exercise)
    off = abs(float(answer) - ref)
    if off <= tol:
        print(
            f"exercise {exercise}: correct ({f'within {tol:.0e} of' if tol else 'equal to'} {source})"
        )
        return True
    print(f"exercise {exercise}: off by {off:.2e} (tolerance {tol:.0e}; the reference is {source})")
    return False


# Lesson 1 and 7's pipe: Texier & Dorbolo's silicone pipe, horizontal, at U = 2 m/s.
def _si_params():
    from fempipe import PipeSI

    return PipeSI(L=0.094, EI=1.8e-5, m=0.0159, M=0.0058, g=9.8, alpha=math.pi / 2).params(U=2.0)


def _bvp(alpha: float, gamma: float, v: float, **kwargs):
    from fempipe.validation.bvp import solve_static_bvp

    return solve_static_bvp(alpha, gamma, v, **kwargs)


# -- lesson 1 ------------------------------------------------------------------


@_exercise("1.1", 1e-5, "theta'(0) of scipy's solve_bvp on the strong form")
def _clamp_moment() -> float:
    p = _si_params()
    return float(_bvp(p.alpha, p.gamma, p.v, tol=1e-11).sol(0.0)[1])


@_exercise("1.2", 1e-10, "the Galerkin solution in exact rational arithmetic")
def _two_polynomials() -> float:
    # phi_i = xi^i: int phi_i' phi_j' = ij / (i + j - 1), int (1 - xi) phi_i = 1/((i+1)(i+2))
    a = [[Fraction(i * j, i + j - 1) for j in (1, 2)] for i in (1, 2)]
    b = [-Fraction(1, (i + 1) * (i + 2)) for i in (1, 2)]
    det = a[0][0] * a[1][1] - a[0][1] * a[1][0]
    c1 = (b[0] * a[1][1] - a[0][1] * b[1]) / det
    c2 = (a[0][0] * b[1] - a[1][0] * b[0]) / det
    return float(c1 * Fraction(1, 4) + c2 * Fraction(1, 16))


@_exercise("1.3", 1e-5, "the closed form -gamma (1/6 + Gamma/2)")
def _end_mass_tip() -> float:
    return -(1 / 6 + 0.5 / 2)  # gamma = 1, Gamma = 0.5


# -- lesson 2 ------------------------------------------------------------------


@_exercise("2.1", 1e-12, "the closed form int_0^0.3 xi dxi (the Green's function of u(1) is xi)")
def _jump_tip() -> float:
    return 0.3**2 / 2


@_exercise("2.2", 1e-5, "|theta(1)| of scipy's solve_bvp started on the buckled branch")
def _buckled() -> float:
    sol = _bvp(math.pi, 10.0, 0.0, guess=lambda x: np.sin(np.pi * x / 2), tol=1e-10)
    return abs(sol.theta_tip)


@_exercise("2.3", 0, "the count 10 n - 1 of P2's couplings and the dense tip column")
def _nonzeros() -> float:
    # 8n + 1 entries of K (3 x 3 per cell, vertices shared), plus the tip dof's column
    # filled in all 2n + 1 rows, of which 3 were there already
    n = 1000
    return 8 * n + 1 + (2 * n + 1 - 3)


# -- lesson 3 ------------------------------------------------------------------


@_exercise("3.1", 1e-12, "h^4 max_p |int_0^(c_p) (t - c_1)(t - c_2)(t - c_3) dt|")
def _cubic_defect() -> float:
    # x^3 minus its interpolant on a cell is h^3 times the Gauss points' node polynomial;
    # whole earlier cells contribute Gauss sums, exact for degree 5
    c = 0.5 * (np.polynomial.legendre.leggauss(3)[0] + 1.0)
    node = np.polynomial.Polynomial.fromroots(c).integ()
    return float(0.25**4 * np.max(np.abs(node(c))))


@_exercise("3.2", 1e-12, "b_p a_pq + b_q a_qp - b_p b_q in exact rational arithmetic")
def _lobatto_defect() -> float:
    c = [Fraction(0), Fraction(1, 2), Fraction(1)]

    def integral(q: int, upper: Fraction) -> Fraction:
        """int_0^upper of the Lagrange polynomial l_q, from its monomial coefficients."""
        coef = [Fraction(1)]  # prod_(m != q) (t - c_m) / (c_q - c_m), lowest degree first
        for m, cm in enumerate(c):
            if m != q:
                shifted = [Fraction(0), *coef]
                coef = [
                    (s - cm * k) / (c[q] - cm) for s, k in zip(shifted, [*coef, 0], strict=True)
                ]
        return sum(k * upper ** (d + 1) / (d + 1) for d, k in enumerate(coef))

    a = [[integral(q, cp) for q in range(3)] for cp in c]
    b = [integral(q, Fraction(1)) for q in range(3)]
    return float(
        max(abs(b[p] * a[p][q] + b[q] * a[q][p] - b[p] * b[q]) for p in range(3) for q in range(3))
    )


@_exercise("3.3", 1e-8, "the closed form 7/3 - 4 sin 1 + 2 cos 1")
def _kinetic() -> float:
    # r_t(xi) = int_0^xi s e^(is) ds = e^(i xi)(1 - i xi) - 1, 2T = int_0^1 |r_t|^2
    return 7 / 3 - 4 * math.sin(1.0) + 2 * math.cos(1.0)


# -- lesson 4 ------------------------------------------------------------------


@_exercise("4.1", 1e-3, "the spectral radius of I - J(q_0)^-1 J(q*)")
def _chord_rate() -> float:
    from fempipe import FiniteElement, Params, PipeModel, solve_static

    model = PipeModel(FiniteElement(8, 3), Params(alpha=math.pi / 2, gamma=5.0, v=2.0))
    q_star = solve_static(model, tol=1e-14).q
    J0 = model.static_jacobian(np.zeros(model.disc.n), dense=True)
    J = model.static_jacobian(q_star, dense=True)
    return float(np.max(np.abs(np.linalg.eigvals(np.eye(len(J)) - np.linalg.solve(J0, J)))))


def _greenhill(lo: float, hi: float) -> float:
    from scipy.optimize import brentq
    from scipy.special import jv

    return brentq(lambda s: jv(-1.0 / 3.0, 2.0 / 3.0 * math.sqrt(s)), lo, hi, xtol=1e-13)


@_exercise("4.2", 1e-3, "the second zero of J_(-1/3)((2/3) sqrt(gamma))")
def _second_buckling() -> float:
    return _greenhill(40.0, 70.0)


@_exercise("4.3", 1e-5, "theta(1) of scipy's solve_bvp")
def _imperfect() -> float:
    sol = _bvp(math.pi + 0.05, 12.0, 0.0, guess=lambda x: 1.5 * np.sin(np.pi * x / 2), tol=1e-10)
    return sol.theta_tip


# -- lesson 5 ------------------------------------------------------------------


@_exercise("5.1", 1e-7, "-mu (beta_1 L)^4 / 2 from 1 + cos x cosh x = 0")
def _kelvin_voigt_shift() -> float:
    from scipy.optimize import brentq

    x = brentq(lambda x: 1.0 + math.cos(x) * math.cosh(x), 1.0, 3.0, xtol=1e-15)
    return -1e-3 * x**4 / 2


def _classical(gamma: float):
    from fempipe.validation.classical import StraightPipe, critical_velocity

    pipe = StraightPipe(beta=0.2, gamma=gamma, mu=1e-3)
    return critical_velocity(pipe, v_max=15.0, method="legendre")


@_exercise("5.2", 1e-4, "the classical straight-pipe theory (Legendre spectral elements)")
def _hanging_vcr() -> float:
    return _classical(18.9).v_cr


@_exercise("5.3", 1e-3, "the classical straight-pipe theory (Legendre spectral elements)")
def _flutter_frequency() -> float:
    return float(_classical(0.0).lam.imag)


# -- lesson 6 ------------------------------------------------------------------


@_exercise("6.1", 1e-6, "E(1) - E(0), the energy's change along the same motion")
def _energy_change() -> float:
    from fempipe import Modal, Params, PipeModel, make_initial_state, simulate

    model = PipeModel(Modal(3), Params(alpha=0.0, v=3.0))
    q0, qd0 = make_initial_state(model, mode=1, amplitude=0.3)
    traj = simulate(model, q0, qd0, 1.0, rtol=1e-9)
    return model.energy(traj.q[-1], traj.qdot[-1]) - model.energy(traj.q[0], traj.qdot[0])


@_exercise("6.2", 1e-12, "the (2, 3) Pade approximant of e^z, Radau IIA's stability function")
def _radau_r() -> float:
    z = -1.0
    return (1 + 2 * z / 5 + z**2 / 20) / (1 - 3 * z / 5 + 3 * z**2 / 20 - z**3 / 60)


# -- lesson 7 ------------------------------------------------------------------


@_exercise("7.1", 0.2, "the theoretical order 2k = 4 of P2's eigenvalues")
def _eigen_order() -> float:
    return 4.0


@_exercise("7.2", 1e-6, "X_g(1) of scipy's solve_bvp with the end mass")
def _end_mass_x() -> float:
    p = _si_params()
    return _bvp(p.alpha, p.gamma, p.v, tol=1e-10, end_mass=0.5).X_tip


@_exercise("7.3", 1e-8, "X_g(1) of scipy's solve_bvp")
def _richardson_x() -> float:
    p = _si_params()
    return _bvp(p.alpha, p.gamma, p.v, tol=1e-11).X_tip


# -- lesson 8 ------------------------------------------------------------------


@_exercise("8.1", 1e-6, "a product of fourth-order Magnus propagators (200 steps, expm)")
def _mathieu_multiplier() -> float:
    from scipy.linalg import expm

    delta, eps, c, steps = 0.25, 0.4, 0.1, 200
    h = 2 * math.pi / steps
    nodes = (0.5 - math.sqrt(3) / 6, 0.5 + math.sqrt(3) / 6)  # Gauss points of one step
    Phi = np.eye(2)
    for k in range(steps):
        A1, A2 = (
            np.array([[0.0, 1.0], [-(delta + eps * math.cos((k + s) * h)), -c]]) for s in nodes
        )
        Phi = expm(h / 2 * (A1 + A2) + math.sqrt(3) / 12 * h * h * (A2 @ A1 - A1 @ A2)) @ Phi
    rho = np.linalg.eigvals(Phi)
    return float(rho[np.argmax(np.abs(rho))].real)


def _hanging_reduced(elements: int):
    from fempipe import FiniteElement, Params, PipeModel
    from fempipe.analyses.parametric import PulsationPencil, ReducedPulsation

    model = PipeModel(
        FiniteElement(elements, 3), Params(alpha=0.0, beta=0.2, gamma=10.0, mu=0.005, v=6.0)
    )
    return ReducedPulsation(PulsationPencil.of(model), 6.0, pairs=3)


@_exercise("8.2", 1e-5, "the threshold located by fempipe on a finer mesh, P3:12")
def _pulsation_threshold() -> float:
    from fempipe.analyses.parametric import Candidate, locate_region
    from fempipe.core.parallel import single_blas_thread

    reduced = _hanging_reduced(12)
    nominal = Candidate("principal", 1, (2,), 2 * reduced.eigenvalues[1].imag)
    with single_blas_thread():
        region, _ = locate_region(reduced, nominal, (27.0, 32.0), [0.15])
    return region.sigma_threshold


@_exercise("8.3", 1e-7, "the monodromy by Radau IIA (1024 steps per period)")
def _hill_outside() -> float:
    from fempipe.analyses.parametric import floquet_multipliers
    from fempipe.core.parallel import single_blas_thread

    with single_blas_thread():
        return float(floquet_multipliers(_hanging_reduced(6), 0.3, 21.0, steps=1024)[0].real)
