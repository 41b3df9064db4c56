"""The discretization contract: basis values, clamp, tip, stiffness and Gram matrices.

References are closed-form integrals of polynomials that the elements
represent exactly (nodal interpolation at scikit-fem's dof locations) and the
orthogonality of the sine modes.
"""

import numpy as np
import pytest

from fempipe.model.discretization import Discretization, FiniteElement, Modal

FE = {
    "P1:7": lambda: FiniteElement(7, 1),
    "P2:graded": lambda: FiniteElement(nodes=[0, 0.1, 0.35, 0.6, 1.0], degree=2),
    "P3:5": lambda: FiniteElement(5, 3),
    "P6:2": lambda: FiniteElement(2, 6),
}


def _interpolate(disc: FiniteElement, f) -> np.ndarray:
    """Coefficients of f (f(0) = 0, in the element space) on the free dofs, by least
    squares on values at 3N points of [0, 1]: exact when f is represented."""
    xs = np.linspace(0.0, 1.0, 3 * disc.n_all)
    P = disc.basis.probes(xs[None, :]).toarray()
    coef = np.linalg.lstsq(P, f(xs), rcond=None)[0]
    assert abs(coef[np.setdiff1d(np.arange(disc.n_all), disc.free)]).max() < 1e-12
    return coef[disc.free]


@pytest.mark.parametrize("name", FE)
def test_fe_integrals_of_a_represented_polynomial(name):
    """theta = xi^k - xi / 2 (degree k, vanishing at 0) is represented exactly by P_k."""
    disc = FE[name]()
    k = disc.degree
    q = _interpolate(disc, lambda x: x**k - 0.5 * x)
    # \\int theta^2, \\int theta'^2 in closed form
    gram = 1 / (2 * k + 1) - 1 / (k + 2) + 1 / 12
    bending = k**2 / (2 * k - 1) - 1 + 0.25
    assert q @ (disc.gram @ q) == pytest.approx(gram, rel=1e-13)
    assert q @ (disc.K @ q) == pytest.approx(bending, rel=1e-13)
    assert disc.tip @ q == pytest.approx(0.5, abs=1e-14)
    x = disc.quad.x
    np.testing.assert_allclose(disc.Phi @ q, x**k - 0.5 * x, atol=1e-14)
    np.testing.assert_allclose(
        disc.evaluate(q, [0.0, 0.3, 1.0]), [0.0, 0.3**k - 0.15, 0.5], atol=1e-14
    )


@pytest.mark.parametrize("name", FE)
def test_fe_clamp_removes_exactly_the_dof_at_the_root(name):
    """Every basis function vanishes at xi = 0; every other dof of scikit-fem is kept."""
    disc = FE[name]()
    assert np.all(disc.evaluate(np.eye(disc.n), 0.0) == 0.0)
    assert disc.n == disc.n_all - 1
    # ... and a function that does not vanish at 0 is not in the space.
    xs = np.linspace(0.0, 1.0, 3 * disc.n_all)
    P = disc.basis.probes(xs[None, :]).toarray()[:, disc.free]
    residual = np.linalg.lstsq(P, 1.0 + xs, rcond=None)[1]
    assert residual[0] > 1e-3


def test_modal_gram_and_stiffness_are_diagonal():
    """\\int phi_i phi_j = delta_ij / 2, \\int phi_i' phi_j' = k_i^2 / 2 delta_ij."""
    disc = Modal(5)
    np.testing.assert_allclose(disc.gram, 0.5 * np.eye(5), atol=1e-14)
    k = (2 * np.arange(1, 6) - 1) * np.pi / 2
    np.testing.assert_allclose(np.diag(disc.K), k**2 / 2, rtol=1e-15)


@pytest.mark.parametrize("disc", [FiniteElement(3, 2), Modal(3)], ids=["fe", "modal"])
def test_both_satisfy_the_protocol(disc):
    assert isinstance(disc, Discretization)
    assert disc.name in ("P2:3", "modal:3")


def test_tip_values_closed_form_and_vectorized():
    """theta = c xi (represented by P3): eta(1) = (1 - cos c)/c,
    X_g(1) = (sin(c + alpha) - sin alpha)/c, Z_g(1) = (cos alpha - cos(c + alpha))/c,
    varsigma(1) = sin(c)/c - 1 (Eqs. (5), (28)); m states at once give the same."""
    from fempipe.model.kinematics import compute_tip, tip_velocity

    disc, alpha = FiniteElement(4, 3), 0.7
    cs = np.array([0.4, -1.3, 2.0])
    Q = np.array([_interpolate(disc, lambda x, c=c: c * x) for c in cs])
    many = compute_tip(disc, Q, alpha)
    for i, c in enumerate(cs):
        one = compute_tip(disc, Q[i], alpha)
        exact = {
            "theta_tip": c,
            "varsigma_tip": np.sin(c) / c - 1.0,
            "eta_tip": (1.0 - np.cos(c)) / c,
            "X_tip": (np.sin(c + alpha) - np.sin(alpha)) / c,
            "Z_tip": (np.cos(alpha) - np.cos(c + alpha)) / c,
        }
        for key, val in exact.items():
            assert isinstance(one[key], float)
            assert one[key] == pytest.approx(val, abs=1e-12)
            assert many[key][i] == pytest.approx(one[key], abs=1e-15)
    # d/dtau at theta_dot = theta / c (the rate of c): d eta(1)/dc etc.
    rates = tip_velocity(disc, Q, Q / cs[:, None], alpha)
    c = cs
    np.testing.assert_allclose(rates["eta_tip"], np.sin(c) / c - (1 - np.cos(c)) / c**2, atol=1e-12)


@pytest.mark.parametrize("n_elements", [1, 8])
def test_evaluate_at_as_many_points_as_the_gauss_rule(n_elements):
    """theta at m points does not depend on m, also when m equals the Gauss points of a cell.

    scikit-fem's ElementLinePp reuses cached values for any call with that many
    points (a broadcasting error before the fix); a P3 mesh of one element also
    built its Phi that way.  The reference is the same points evaluated as
    part of a larger array, and a cubic that P3 reproduces exactly.
    """
    disc = FiniteElement(n_elements, 3)
    q = np.linalg.lstsq(disc.Phi.toarray(), disc.quad.x**3 - 3 * disc.quad.x, rcond=None)[0]
    xs = np.linspace(0.0, 1.0, disc.n_gauss)
    values = disc.evaluate(q, xs)
    assert np.allclose(values, disc.evaluate(q, np.append(xs, 0.5))[:-1], atol=1e-14)
    assert np.allclose(values, xs**3 - 3 * xs, atol=1e-12)


def test_higher_degree_elements_stay_picklable():
    """Building a second element of degree >= 3 must not make the first one's scikit-fem
    basis unpicklable (one element class per process, found by name on unpickling)."""
    import pickle

    first = FiniteElement(n_elements=4, degree=3)
    second = FiniteElement(n_elements=2, degree=4)
    for disc in (first, second):
        assert pickle.loads(pickle.dumps(disc)).name == disc.name
        back = pickle.loads(pickle.dumps(disc.basis.elem))
        assert type(back) is type(disc.basis.elem)
