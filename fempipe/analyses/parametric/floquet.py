"""Floquet multipliers of the straight pipe under a pulsating flow v0 (1 + sigma sin(omega tau)).

At alpha = 0, pi the straight state stays in place and small motions obey (Eq. (20))

    M q'' + (C0 + v C1) q' + (K0 + v^2 K2 + dv/dtau K3) q = 0;

the multipliers are the eigenvalues of the monodromy over 2 pi / omega, on a Ritz basis of
the lowest modes, by Radau IIA.  Derivation and convergence: docs/theory/parametric.md.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg as sla

from fempipe.analyses.stability.hopf.pipe import dense
from fempipe.analyses.stability.linear import straight_is_static, straight_pencil
from fempipe.model.plane.operators import PipeModel
from fempipe.solvers.radau import A as RADAU_A
from fempipe.solvers.radau import C as RADAU_C

__all__ = ["PulsationPencil", "ReducedPulsation", "floquet_multipliers"]


@dataclass(frozen=True)
class PulsationPencil:
    """The straight pipe's linear matrices, split by their dependence on the flow.

    Attributes
    ----------
    M, K0, K2, K3, C0, C1 : ndarray, shape (n, n)
        K(tau) = K0 + v^2 K2 + (dv/dtau) K3 and C(tau) = C0 + v C1 at theta = 0.
    """

    M: np.ndarray
    K0: np.ndarray
    K2: np.ndarray
    K3: np.ndarray
    C0: np.ndarray
    C1: np.ndarray

    @classmethod
    def of(cls, model: PipeModel) -> PulsationPencil:
        """The matrices of ``model`` (v ignored) at theta = 0; ValueError unless alpha = 0, pi."""
        if not straight_is_static(model.params):
            raise ValueError(
                f"alpha = {model.params.alpha:.6g}: the straight state is a solution only for "
                "alpha = 0 or pi (a bent pipe: compute_parametric_chart about its forced response)"
            )
        # The steady terms are the stability analysis's straight pencil; only the flow
        # acceleration's stiffness is new: the Jacobian's change with dv/dtau at v = 0.
        straight = straight_pencil(model)
        zero = np.zeros(model.n)
        still = model.with_params(replace(model.params, v=0.0))
        Ka = dense(still.jacobians(zero, zero, zero, v_dot=1.0)[0])
        return cls(
            M=dense(straight.M),
            K0=dense(straight.K0),
            K2=dense(straight.K2),
            K3=Ka - dense(still.jacobians(zero, zero, zero)[0]),
            C0=dense(straight.C0),
            C1=dense(straight.C1),
        )


class ReducedPulsation:
    """The pulsating problem on the low modes of the mean flow and their static corrections
    (a Ritz basis, M-orthonormal; docs/theory/parametric.md), integrated over one period by
    Radau IIA with fixed steps; at sigma = 0 the multipliers are exactly exp(lambda T).

    Parameters
    ----------
    pencil : PulsationPencil
    v0 : float
    pairs : int, optional
        Keep this many eigenvectors of lowest |lambda| (a complex pair counts once).
    targets : sequence of complex, optional
        Instead, those nearest these eigenvalues.

    Attributes
    ----------
    eigenvalues : ndarray
        The kept eigenvalues of the mean problem, Im >= 0.
    """

    def __init__(
        self,
        pencil: PulsationPencil,
        v0: float,
        pairs: int | None = None,
        targets: Sequence[complex] | None = None,
    ) -> None:
        n = pencil.M.shape[0]
        if (pairs is None) == (targets is None):
            raise ValueError("give either pairs or targets")
        if pairs is not None and pairs < 1:
            raise ValueError(f"pairs must be >= 1, got {pairs}")
        K = pencil.K0 + v0 * v0 * pencil.K2
        C = pencil.C0 + v0 * pencil.C1
        Minv = np.linalg.inv(pencil.M)
        A0 = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ C]])
        lam, X = sla.eig(A0)
        upper = np.flatnonzero(lam.imag >= 0)
        if targets is None:
            kept = upper[np.argsort(np.abs(lam[upper]))][:pairs]
        else:
            picks = [upper[np.argmin(np.abs(lam[upper] - complex(t)))] for t in targets]
            kept = np.array(sorted(set(picks), key=picks.index))
        self.eigenvalues = lam[kept]
        modes = X[:n, kept]
        parts = [modes.real, modes.imag[:, np.abs(modes.imag).max(axis=0) > 0]]
        shapes = np.column_stack(parts)
        loads = np.column_stack([pencil.K2 @ shapes, pencil.K3 @ shapes, pencil.C1 @ shapes])
        basis = np.column_stack([shapes, np.linalg.solve(K, loads)])
        norms = np.linalg.norm(basis, axis=0)
        basis = basis[:, norms > 0]  # a term that vanishes (beta = 0: no Coriolis) adds nothing
        U, S, _ = np.linalg.svd(basis / norms[norms > 0], full_matrices=False)
        basis = U[:, S > 1e-10 * S[0]]
        L = np.linalg.cholesky(basis.T @ pencil.M @ basis)
        Q = np.linalg.solve(L, basis.T).T  # Q^T M Q = I
        self.v0, self.Q = float(v0), Q

        def proj(Y: np.ndarray) -> np.ndarray:
            return Q.T @ Y @ Q

        m = Q.shape[1]
        Mr = proj(pencil.M)  # the identity up to round-off: solved with, not assumed

        def first_order(K, C, identity: bool) -> np.ndarray:
            F = np.zeros((2 * m, 2 * m))
            if identity:
                F[:m, m:] = np.eye(m)
            if K is not None:
                F[m:, :m] = -np.linalg.solve(Mr, proj(K))
            if C is not None:
                F[m:, m:] = -np.linalg.solve(Mr, proj(C))
            return F

        #: A(tau) = F[0] + v F[1] + v^2 F[2] + (dv/dtau) F[3]
        self.F = np.stack(
            [
                first_order(pencil.K0, pencil.C0, True),
                first_order(None, pencil.C1, False),
                first_order(pencil.K2, None, False),
                first_order(pencil.K3, None, False),
            ]
        )

    @property
    def size(self) -> int:
        """The dimension of the first-order system."""
        return self.F.shape[-1]

    def monodromy(self, sigma: float, omega: float, steps: int = 128) -> np.ndarray:
        """The state-transition matrix over one period 2 pi / omega (``steps`` Radau IIA steps).

        The problem being linear, the stage equations of every step are solved at once,
        independently of the state, on the velocities alone (A(tau) = [[0, I], [-K, -C]]: the
        stage positions are q0 + h (a x I) P, docs/theory/parametric.md); the steps'
        propagators are then multiplied.
        """
        if omega <= 0:
            raise ValueError(f"omega must be > 0, got {omega}")
        if steps < 1:
            raise ValueError(f"steps must be >= 1, got {steps}")
        m = self.size // 2
        h = 2 * math.pi / omega / steps
        tau = (np.arange(steps)[:, None] + RADAU_C[None, :]) * h  # (steps, 3)
        v = self.v0 * (1.0 + sigma * np.sin(omega * tau))
        v_dot = self.v0 * sigma * omega * np.cos(omega * tau)
        coef = np.stack([np.ones_like(v), v, v * v, v_dot], axis=-1)  # (steps, 3, 4)
        lower = np.einsum("sjc,cab->sjab", coef, self.F[:, m:])  # [-K, -C] at the stages
        K, C = -lower[..., :m], -lower[..., m:]
        a, eye = RADAU_A, np.eye(m)
        # (I + h (a x I) C + h^2 (a x I) K (a x I)) P = p0 - h (a x I) K q0, for (q0, p0) = I
        big = h * np.einsum("jl,slab->sjalb", a, C) + h * h * np.einsum(
            "jk,kl,skab->sjalb", a, a, K
        )
        big = big.reshape(steps, 3 * m, 3 * m) + np.eye(3 * m)
        rhs = np.zeros((steps, 3, m, 2 * m))
        rhs[..., :m] = -h * np.einsum("jk,skab->sjab", a, K)
        rhs[..., m:] = eye
        P = np.linalg.solve(big, rhs.reshape(steps, 3 * m, 2 * m)).reshape(steps, 3, m, 2 * m)
        # stiffly accurate: a step ends at its last stage
        step = np.empty((steps, 2 * m, 2 * m))
        step[:, :m] = h * np.einsum("l,slab->sab", a[2], P)
        step[:, :m, :m] += eye
        step[:, m:] = P[:, 2]
        Phi = np.eye(2 * m)
        for k in range(steps):
            Phi = step[k] @ Phi
        return Phi


def floquet_multipliers(
    reduced: ReducedPulsation, sigma: float, omega: float, steps: int = 128
) -> np.ndarray:
    """The Floquet multipliers, largest modulus first."""
    rho = np.linalg.eigvals(reduced.monodromy(sigma, omega, steps))
    return rho[np.argsort(-np.abs(rho))]
