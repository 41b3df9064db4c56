"""A classical beam-mode Galerkin critical velocity, as a user would write it (numpy, scipy only).

The timing baseline of ``fempipe bench critical_vs_classical``: the straight hanging (or
standing) cantilevered pipe conveying fluid of Paidoussis (1970) and Gregory & Paidoussis
(1966); Paidoussis, *Fluid-Structure Interactions* vol. 1 (1998), Eq. (3.70) and Appendix D,

    eta'''' + mu eta_dot'''' + [v^2 - s gamma (1 - xi)] eta'' + 2 sqrt(beta) v eta_dot'
        + s gamma eta' + eta_ddot = 0     (s = +1 hanging, -1 standing),

on N clamped-free beam modes with the closed-form coefficients b_sr, c_sr, d_sr.  It is run as
a script by its path and imports nothing of fempipe:

    python classical_baseline.py --beta 0.2 --gamma 10 --n 40 [--eigenvalues-at 3]

prints JSON: v_cr (a scan of v with ``--step``, then Brent on the largest real part of the 2N
eigenvalues of the first-order system), the frequency there, and optionally the eigenvalues
at one v sorted by |lambda|.  docs/theory/independent.md, "The classical linear theory".
"""

import argparse
import json

import numpy as np
import scipy.linalg as sla
from scipy.optimize import brentq


def beam_coefficients(n):
    """lambda_r and Paidoussis' b_sr, c_sr, d_sr (Appendix D) for r, s = 1..n."""
    lam = np.array(
        [
            brentq(lambda x: np.cos(x) + 1 / np.cosh(x), (r - 1) * np.pi + 1e-9, r * np.pi)
            for r in range(1, n + 1)
        ]
    )
    e = np.exp(-lam)  # sigma = (sinh - sin)/(cosh + cos) without overflow
    sig = (1 - 2 * np.sin(lam) * e - e * e) / (1 + 2 * np.cos(lam) * e + e * e)
    ls, lr = lam[:, None], lam[None, :]  # rows s, columns r
    sgn = (-1.0) ** (np.arange(n)[:, None] + np.arange(n)[None, :])
    off = ~np.eye(n, dtype=bool)
    ratio = np.where(off, ls / lr, 0.0)
    b = np.where(off, 4 / (ratio**2 + sgn), 2.0)
    ls_s, lr_s = (lam * sig)[:, None], (lam * sig)[None, :]
    c = np.where(off, 4 * (lr_s - ls_s) / np.where(off, sgn - ratio**2, 1.0), 0.0)
    c[~off] = lam * sig * (2 - lam * sig)
    r4 = np.where(off, 1 - ratio**4, 1.0)
    d = np.where(off, 4 * (lr_s - ls_s + 2) * sgn / r4 - (ratio**4 + 3) / r4 * b, 0.0)
    d[~off] = np.diag(c) / 2
    return lam, b, c, d


def make_eigenvalues(n, beta, gamma, mu=0.0, standing=False):
    """lambda(v): the 2N eigenvalues of [[0, I], [-K, -C]] (M = I), eta ~ exp(lambda tau)."""
    lam, b, c, d = beam_coefficients(n)
    s = -1.0 if standing else 1.0
    L4 = np.diag(lam**4)
    K0 = L4 + s * gamma * (b - c + d)  # -s gamma (1 - xi) eta'' + s gamma eta'
    Z, eye = np.zeros((n, n)), np.eye(n)

    def eigenvalues(v):
        K, C = K0 + v * v * c, mu * L4 + 2 * np.sqrt(beta) * v * b
        return sla.eig(np.block([[Z, eye], [-K, -C]]), right=False)

    return eigenvalues


def critical_velocity(eigenvalues, v_max=10.0, step=0.1, xtol=1e-12):
    """First v where max Re lambda turns positive: a scan of v, then Brent."""

    def g(v):
        return eigenvalues(v).real.max()

    grid = np.arange(step, v_max + step / 2, step)  # v = 0 is undamped: Re = 0 to round-off
    g_prev = g(grid[0])
    for v0, v1 in zip(grid[:-1], grid[1:], strict=True):
        g1 = g(v1)
        if g_prev < 0 <= g1:
            v_cr = brentq(g, v0, v1, xtol=xtol)
            lam = eigenvalues(v_cr)
            return v_cr, float(abs(lam[np.argmax(lam.real)].imag))
        g_prev = g1
    return None, None


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    for name, default in (
        ("beta", 0.2),
        ("gamma", 10.0),
        ("mu", 0.0),
        ("v-max", 10.0),
        ("step", 0.1),
    ):
        ap.add_argument("--" + name, type=float, default=default)
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--standing", action="store_true")
    ap.add_argument("--eigenvalues-at", type=float, default=None)
    a = ap.parse_args()
    eig = make_eigenvalues(a.n, a.beta, a.gamma, a.mu, a.standing)
    v_cr, freq = critical_velocity(eig, a.v_max, a.step)
    out = {"v_cr": v_cr, "frequency": freq, "n_modes": a.n}
    if a.eigenvalues_at is not None:
        lam = eig(a.eigenvalues_at)
        lam = lam[np.argsort(np.abs(lam))]
        out["eigenvalues"] = [[float(x.real), float(x.imag)] for x in lam]
    print(json.dumps(out))
