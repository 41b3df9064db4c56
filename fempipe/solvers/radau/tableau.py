"""The Radau IIA (s = 3) tableau and RADAU5's constants.

The constants, Newton limits, step-size limits and the predictive controller are Hairer &
Wanner's RADAU5 (Solving ODEs II, Sec. IV.8) as transcribed in ``scipy.integrate.Radau``.
A and its eigendecomposition are computed here, because the stages are solved for the
accelerations of the second-order system.
"""

from __future__ import annotations

import math

import numpy as np

_S6 = math.sqrt(6.0)
#: Nodes c_i of the stages (c_3 = 1: stiffly accurate).
C = np.array([(4.0 - _S6) / 10.0, (4.0 + _S6) / 10.0, 1.0])
#: The Butcher matrix a_ij.
A = np.array(
    [
        [(88.0 - 7.0 * _S6) / 360.0, (296.0 - 169.0 * _S6) / 1800.0, (-2.0 + 3.0 * _S6) / 225.0],
        [(296.0 + 169.0 * _S6) / 1800.0, (88.0 + 7.0 * _S6) / 360.0, (-2.0 - 3.0 * _S6) / 225.0],
        [(16.0 - _S6) / 36.0, (16.0 + _S6) / 36.0, 1.0 / 9.0],
    ]
)
#: a^2: the positions Q_i = q0 + c_i h p0 + h^2 sum_j (a^2)_ij A_j.
A2 = A @ A
#: Error-estimate weights and the real eigenvalue 1/g_0 of A^-1 (RADAU5).
E = np.array([-13.0 - 7.0 * _S6, -13.0 + 7.0 * _S6, -1.0]) / 3.0
MU_REAL = 3.0 + 3.0 ** (2.0 / 3.0) - 3.0 ** (1.0 / 3.0)


def diagonalise_a():
    """``a = T diag(g) T^-1``: (g, T, T^-1), the real eigenvalue first, then g_1 with
    positive imaginary part and g_2 = conj(g_1)."""
    lam, T = np.linalg.eig(A)
    order = np.argsort(np.abs(lam.imag))  # real eigenvalue first
    lam, T = lam[order], T[:, order]
    if lam[1].imag < 0:  # keep g_1 with positive imaginary part, g_2 = conj
        lam[[1, 2]] = lam[[2, 1]]
        T[:, [1, 2]] = T[:, [2, 1]]
    T[:, 0] = T[:, 0].real
    return lam, T, np.linalg.inv(T)


#: The eigenvalues g_k of a, its eigenvectors T and T^-1 (:func:`diagonalise_a`).
EIGENVALUES, T, TI = diagonalise_a()
# The stage accelerations from the transformed increments (Newton of the
# stage equations): dacc = -(T_0 dV_0 + 2 Re(T_1 dV_1)), with T_0 real.
T0 = T[:, 0].real[:, None]
T1R, T1I = 2.0 * T[:, 1].real[:, None], 2.0 * T[:, 1].imag[:, None]

NEWTON_MAXITER = 6
#: A step whose Newton iteration needed more than two iterations at a
#: contraction rate above this gets a fresh Jacobian (RADAU5's THET, 1e-3).
JACOBIAN_RATE = 1e-3
MIN_FACTOR, MAX_FACTOR = 0.2, 10.0
