"""Parts (a) and (b) of the case ``out_of_plane`` (the straight pipe, the buckled standing
pipe's neutral rotation) and the spectral helpers the parts share.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg as sla

from fempipe.analyses import stability
from fempipe.analyses.statics import solve_sagged, solve_static
from fempipe.model.discretization import discretization_from_name
from fempipe.model.out_of_plane.model import OutOfPlaneOperators, build_out_of_plane_model
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel

from . import lateral
from .checks import Table
from .evaluate import measure

#: Kelvin-Voigt roots near -1/mu: a cluster of nearly equal roots (one per
#: unresolved mode), sensitive at the square root of round-off; the spectra
#: are compared outside |lambda + 1/mu| < CLUSTER / mu.
CLUSTER = 0.05
#: Only these eigenvalues are compared (the lowest eight modes or so).
LAM_MAX = 1000.0


def _disc(name: str):
    """The discretization named ``name`` (``"P3:32"``, ``"modal:8"``)."""
    return discretization_from_name(name)


def dense(A) -> np.ndarray:
    """``A`` as a dense float array (sparse matrices are expanded)."""
    return A.toarray() if hasattr(A, "toarray") else np.asarray(A, dtype=float)


def _rel(a, b) -> float:
    """The relative Frobenius distance of ``a`` from ``b``."""
    return float(np.linalg.norm(dense(a) - dense(b)) / np.linalg.norm(dense(b)))


def pencil_eigenvalues(K, C, M, vectors=False):
    """All eigenvalues (and vectors) of (K + lambda C + lambda^2 M) x = 0 by QZ on the first-order
    pencil (the companion of M^-1 K loses the eigenvalue near zero to 6e-6 with Kelvin-Voigt).
    """
    n = K.shape[0]
    I, Z = np.eye(n), np.zeros((n, n))
    A = np.block([[Z, I], [-dense(K), -dense(C)]])
    B = np.block([[I, Z], [Z, dense(M)]])
    if not vectors:
        return sla.eigvals(A, B)
    lam, X = sla.eig(A, B)
    return lam, X[:n]


def nearest_distance(lam: np.ndarray, ref: np.ndarray) -> float:
    """max over ref of the relative distance to the nearest lam."""
    return float(max(np.min(np.abs(lam - r)) / abs(r) for r in ref))


def in_cluster(lam: np.ndarray, mu: float) -> np.ndarray:
    """Mask of the eigenvalues in the Kelvin-Voigt cluster |lambda + 1/mu| < CLUSTER / mu."""
    if mu <= 0.0:
        return np.zeros(lam.shape, dtype=bool)
    return np.abs(lam + 1.0 / mu) < CLUSTER / mu


def outside_cluster(lam: np.ndarray, mu: float) -> np.ndarray:
    """The eigenvalues with |lambda| < LAM_MAX outside the Kelvin-Voigt cluster."""
    return lam[(np.abs(lam) < LAM_MAX) & ~in_cluster(lam, mu)]


def _guess_q(model: PipeModel, tip: float) -> np.ndarray:
    """Coefficients of theta = tip xi (2 - xi) (least squares at the quadrature points)."""
    x = model.disc.quad.x
    return np.linalg.lstsq(dense(model.disc.Phi), tip * x * (2.0 - x), rcond=None)[0]


def refinement_slope(ns, errs) -> float:
    """log-log slope of the last refinement."""
    return float(-math.log(errs[-1] / errs[-2]) / math.log(ns[-1] / ns[-2]))


# (a) the straight pipe: out of the plane = in the plane


def identity_checks(ref):
    var = dict(ref.value("variants"))
    var["springs"] = tuple(tuple(s) for s in var["springs"])
    base = Params(alpha=0.0, **ref.value("paper_case"), **var)
    st = ref.value("standing")
    states = {"hanging": base, "standing": replace(base, alpha=math.pi, **st)}
    checks, rows = [], []
    for where, p in states.items():
        worst_m, worst_l, worst_c = 0.0, 0.0, 0.0
        for name in ref.value("identity_discretizations"):
            m = PipeModel(_disc(name), p)
            mo = build_out_of_plane_model(m)
            q = solve_sagged(m).q
            mats = [
                _rel(a, b) for a, b in zip(mo.linearization(q), m.linearization(q), strict=True)
            ]
            mats.append(_rel(mo.hysteretic_stiffness(q), m.hysteretic_stiffness(q)))
            si, so = stability.compute_spectrum(m, q), stability.compute_spectrum(mo, q)
            same_modes = bool(np.array_equal(si.mode, so.mode))
            d = np.abs(so.lam - si.lam) / np.abs(si.lam) if same_modes else np.array([np.inf])
            out = ~in_cluster(si.lam, p.mu)
            d_out = float(d[out].max()) if same_modes else math.inf
            d_in = float(d[~out].max()) if same_modes and (~out).any() else 0.0
            worst_m, worst_l = max(worst_m, max(mats)), max(worst_l, d_out)
            worst_c = max(worst_c, d_in)
            rows.append((where, name, float(np.abs(q).max()), *mats, si.lam.size, d_out, d_in))
        fields = {"where": where, "p": p}
        checks.append(measure("identity_matrices_{where}", worst_m, **fields))
        checks.append(measure("identity_spectrum_{where}", worst_l, cluster=worst_c, **fields))
    table = ref.table("identity", tuple(rows))
    return checks, [table]


# (b) the buckled standing pipe: the neutral rotation mode


def _buckled_fe(p: Params, name: str, tip: float):
    m = PipeModel(_disc(name), p)
    q = solve_static(m, q0=_guess_q(m, tip)).q
    return m, q


@dataclass(frozen=True)
class _NeutralSpectrum:
    """A spectrum of the buckled pipe: its eigenvalue nearest zero and the others."""

    where: str  # the pipe and discretization, for the claims
    lam0: complex  # the eigenvalue nearest zero
    cos: float  # |cos angle| of its eigenvector with the expected neutral mode
    others: np.ndarray  # the other eigenvalues (a window of them)


def _fe_neutral(p: Params, name: str, tip: float) -> _NeutralSpectrum:
    """fempipe on the reference mesh: lambda = 0 exactly, eigenvector the projection of sin theta."""
    m, q = _buckled_fe(p, name, tip)
    ops = OutOfPlaneOperators(m)
    mats = ops.matrices(q)
    lam, X = pencil_eigenvalues(mats.K, mats.C, mats.M, vectors=True)
    i0 = int(np.argmin(np.abs(lam)))
    x = ops.neutral_mode(q)
    cos = abs(np.vdot(X[:, i0], x)) / (np.linalg.norm(X[:, i0]) * np.linalg.norm(x))
    where = (
        f"buckled standing pipe (α = π, γ = {p.gamma:g}, v = {p.v:g}, μ = {p.mu:g}, "
        f"θ(1) = {float(m.disc.tip @ q):.6f}), {m.disc.name}"
    )
    others = np.delete(lam, i0)
    return _NeutralSpectrum(where, lam[i0], cos, others[np.abs(others) < LAM_MAX])


def _strong_neutral(p: Params, degree: int, tip: float) -> _NeutralSpectrum:
    """The strong form about solve_bvp's buckled state (``where``: its discretization)."""
    st = lateral.static_state(p, guess=lambda xi: tip * xi * (2.0 - xi))
    disc = lateral.HermiteSpectral(degree)
    K, C, M, parts = disc.matrices(st)
    lam_s, W = lateral.eigen(K, C, M, bending=parts["bending"], vectors=True)
    j0 = int(np.argmin(np.abs(lam_s)))
    a = disc.project(p, st.eta)
    cos_s = abs(np.vdot(W[:, j0], M @ a)) / math.sqrt(
        abs(np.vdot(W[:, j0], M @ W[:, j0])) * (a @ M @ a)
    )
    rest_s = np.delete(lam_s, j0)
    rest_s = rest_s[np.abs(rest_s) < 100.0]  # the three lowest modes
    where = f"{disc.label()}, θ(1) = {st.theta_tip:.6f} by solve_bvp"
    return _NeutralSpectrum(where, lam_s[j0], cos_s, rest_s)


def _neutral_checks(fe: _NeutralSpectrum, strong: _NeutralSpectrum) -> list:
    """The neutral mode of fempipe and of the strong form, and their other eigenvalues."""
    where = fe.where
    return [
        measure("neutral_eigenvalue", abs(fe.lam0), where=where),
        measure("neutral_eigenvector", 1.0 - fe.cos, where=where),
        measure("buckled_rest_stable", float(fe.others.real.max()), where=where, lam_max=LAM_MAX),
        measure(
            "strong_neutral_mode",
            max(abs(strong.lam0), 1.0 - strong.cos),
            strong=strong.where,
            lam0=abs(strong.lam0),
        ),
        measure(
            "buckled_vs_strong",
            nearest_distance(fe.others, strong.others),
            where=where,
            n=strong.others.size,
        ),
    ]


def _residual_orders(ref, p: Params, tip: float, quick: bool) -> tuple[list, Table]:
    """The residual of the uncorrected K on the projection of sin theta: its order."""
    order = ref.value("neutral_order")
    rows, checks = [], []
    for deg, meshes in ref.value("neutral_meshes", quick).items():
        res = []
        for n in meshes:
            mm, qq = _buckled_fe(p, f"{deg}:{n}", tip)
            res.append(OutOfPlaneOperators(mm).matrices(qq).neutral_residual)
        slopes = [
            refinement_slope(meshes[k : k + 2], res[k : k + 2]) for k in range(len(meshes) - 1)
        ]
        rows.append((deg, ", ".join(map(str, meshes)), ", ".join(f"{r:.3g}" for r in res),
                     ", ".join(f"{s:.2f}" for s in slopes), order))  # fmt: skip
        ok = bool(np.all(np.diff(res) < 0) and abs(slopes[-1] - order) <= 0.3)
        fields = {"p": p, "meshes": meshes, "last": meshes[-1], "slopes": slopes}
        checks.append(
            measure(
                "neutral_residual_order_{degree}",
                ok=ok,
                degree=deg,
                residual=res[-1],
                slope=slopes[-1],
                **fields,
            )
        )
    table = ref.table("neutral", rows, gamma=p.gamma, v=p.v)
    return checks, table


def buckled_checks(ref, quick: bool):
    """(b) The neutral rotation of the buckled standing pipe, by fempipe and the strong form, and
    the order at which the uncorrected stiffness's residual falls.
    """
    b = dict(ref.value("buckled"))
    tip = b.pop("guess_tip")
    p = Params(beta=ref.value("paper_case")["beta"], **b)
    fe = _fe_neutral(p, ref.value("buckled_fe"), tip)
    strong = _strong_neutral(p, ref.value("spectral_p")[0], tip)
    order_checks, table = _residual_orders(ref, p, tip, quick)
    return _neutral_checks(fe, strong) + order_checks, [table]
