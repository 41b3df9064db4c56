"""
Lesson 8: Floquet theory on a pipe
==================================

What you should see: a linear equation with periodic coefficients, the damped Mathieu
equation, integrated over one period from the identity: its monodromy matrix, whose
eigenvalues (the Floquet multipliers) decide whether its solutions grow, and the principal
tongue near delta = 1/4 where a multiplier leaves the unit circle at -1; then the same on
the hanging pipe of Paidoussis & Issid under a pulsating flow
v(tau) = v0 (1 + sigma sin(omega tau)): the region of parametric resonance of its second mode
near 2 omega_2, its threshold and its boundary; and two independent checks, Hill's method
(the Floquet problem in the frequency domain) giving the same multipliers, and Eq. (20)
integrated with the pulsating flow, growing by the largest multiplier per period inside the
region and decaying outside.  The theory: :doc:`Parametric resonance </theory/parametric>`.
"""

# %%
# 1. The damped Mathieu equation by hand
# --------------------------------------
# x'' + c x' + (delta + eps cos t) x = 0 has coefficients of period T = 2 pi.  In first-order
# form y' = A(t) y, y = (x, x'), the fundamental matrix started from the identity gives after
# one period the *monodromy matrix* Phi(T): every solution obeys y(t + T) = Phi(T) y(t), so
# y(kT) = Phi(T)^k y(0) and the solutions decay when every eigenvalue rho of Phi(T) (a Floquet
# multiplier) lies inside the unit circle.  Liouville's formula fixes their product,
#
# .. math::
#
#    \rho_1 \rho_2 = \det \Phi(T) = \exp \int_0^T \operatorname{tr} A \, dt = e^{-cT} ,
#
# so they are a complex pair of modulus :math:`e^{-cT/2}` (stable) or two real numbers of one
# sign, the larger of which may leave the circle.  Near delta = 1/4 it leaves at -1: the growing
# solution has the period 2T, half the frequency of the excitation.  Averaging x = a cos(t/2) +
# b sin(t/2) gives the exponent :math:`s = \sqrt{\varepsilon^2/4 - (\delta - 1/4)^2} - c/2`:
# the tongue's edges :math:`\delta = 1/4 \pm \sqrt{\varepsilon^2 - c^2}/2`, its tip at eps = c.

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

import fempipe
from fempipe.analyses.parametric import (
    PulsationPencil,
    ReducedPulsation,
    compute_parametric_chart,
    floquet_multipliers,
)
from fempipe.core.parallel import single_blas_thread
from fempipe.course import check  # noqa: F401 (the exercises' solutions use it)
from fempipe.plotting.scripts import show_or_save


def mathieu_monodromy(delta: float, eps: float, c: float) -> np.ndarray:
    """Phi(2 pi) of x'' + c x' + (delta + eps cos t) x = 0: the 2 x 2 fundamental matrix."""

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        A = np.array([[0.0, 1.0], [-(delta + eps * np.cos(t)), -c]])
        return (A @ y.reshape(2, 2)).ravel()

    sol = solve_ivp(
        rhs, (0.0, 2 * np.pi), np.eye(2).ravel(), method="DOP853", rtol=1e-11, atol=1e-13
    )
    return sol.y[:, -1].reshape(2, 2)


c = 0.1
rho = np.linalg.eigvals(mathieu_monodromy(0.25, 0.2, c))
liouville = abs(np.prod(rho) - np.exp(-2 * np.pi * c))
print(f"delta = 1/4, eps = 0.2, c = {c}: multipliers {rho.real.round(6)}")
print(f"rho_1 rho_2 - exp(-c T) = {liouville:.1e} (Liouville)")

# The tongue: every (delta, eps) of a grid at once, one solve_ivp on all their fundamental
# matrices, the largest modulus of the eigenvalues of each.
D, E = np.meshgrid(np.linspace(0.0, 0.5, 61), np.linspace(0.0, 0.6, 41))
d, e = D.ravel(), E.ravel()


def rhs_grid(t: float, y: np.ndarray) -> np.ndarray:
    x1, u1, x2, u2 = y.reshape(4, d.size)
    k = d + e * np.cos(t)
    return np.concatenate([u1, -c * u1 - k * x1, u2, -c * u2 - k * x2])


start = np.concatenate([np.ones(d.size), np.zeros(d.size), np.zeros(d.size), np.ones(d.size)])
end = solve_ivp(rhs_grid, (0.0, 2 * np.pi), start, method="DOP853", rtol=1e-10, atol=1e-12)
x1, u1, x2, u2 = end.y[:, -1].reshape(4, d.size)
Phis = np.stack([np.stack([x1, x2], -1), np.stack([u1, u2], -1)], -2)  # (points, 2, 2)
largest_grid = np.abs(np.linalg.eigvals(Phis)).max(axis=1).reshape(D.shape)


def mathieu_margin(eps: float) -> float:
    """log of the largest modulus at delta = 1/4 (> 0: unstable)."""
    return float(np.log(np.abs(np.linalg.eigvals(mathieu_monodromy(0.25, eps, c))).max()))


eps_threshold = brentq(mathieu_margin, 0.05, 0.3, xtol=1e-10)
print(f"the tongue opens at eps = {eps_threshold:.5f} (averaging: eps = c = {c})")

fig, ax = plt.subplots(figsize=(5, 3.4), layout="constrained")
cs = ax.contourf(D, E, largest_grid, levels=np.linspace(0.7, 2.0, 14), extend="max")
fig.colorbar(cs, ax=ax, label="largest |rho|")
ax.contour(D, E, largest_grid, levels=[1.0], colors="k", linewidths=1.2)
eps_line = np.linspace(c, 0.6, 50)
for sign in (-1, 1):
    ax.plot(0.25 + sign * np.sqrt(eps_line**2 - c**2) / 2, eps_line, "w--", lw=1)
ax.set_xlabel("delta")
ax.set_ylabel("eps")
ax.set_title(
    f"x'' + {c} x' + (delta + eps cos t) x = 0: |rho| = 1 (black), averaging (dashed)", fontsize=8
)

# %%
# 2. The pipe's monodromy
# -----------------------
# The hanging pipe (alpha = 0) of Paidoussis & Issid: beta = 0.2, gamma = 10, mu = 0.005,
# mean flow v0 = 6 (its critical velocity is 7.1).  The straight state stays a solution under
# the pulsating flow, and small motions obey M q'' + (C0 + v C1) q' + (K0 + v^2 K2 + v' K3)
# q = 0: Coriolis, follower force and flow acceleration (the matrices of
# :class:`~fempipe.analyses.parametric.PulsationPencil`).  First the mean flow's spectrum:
# the first mode is damped beyond the ratio 1/sqrt 2 (no resonator), the second, the flutter
# mode, oscillates at omega_2 = Im lambda_2.
v0 = 6.0
params = fempipe.Params(alpha=0.0, beta=0.2, gamma=10.0, mu=0.005, v=v0)
model = fempipe.PipeModel(fempipe.FiniteElement(6, 3), params)
mean = fempipe.compute_spectrum(model, np.zeros(model.n))
upper = mean.lam.imag > 0
for lam, k in list(zip(mean.lam[upper], mean.mode[upper], strict=True))[:3]:
    print(f"mode {k}: lambda = {lam.real:.4f} + {lam.imag:.4f}i")
omega_2 = float(mean.lam[upper][list(mean.mode[upper]).index(2)].imag)
print(f"2 omega_2 = {2 * omega_2:.4f}")

# The monodromy is computed on a Ritz basis of the three lowest modes of the mean flow with
# their static corrections (:class:`~fempipe.analyses.parametric.ReducedPulsation`), by the
# Radau IIA method with 128 fixed steps per period.  At sigma = 0 the multipliers are
# :math:`e^{\lambda_k T}`, to the error of those steps.  The matrices are small (36 x 36):
# one BLAS thread is faster than several, as in fempipe's own loops.
pencil = PulsationPencil.of(model)
reduced = ReducedPulsation(pencil, v0, pairs=3)


def multipliers(sigma: float, omega: float, steps: int = 128) -> np.ndarray:
    """The pipe's Floquet multipliers, largest modulus first."""
    with single_blas_thread():
        return floquet_multipliers(reduced, sigma, omega, steps)


T_check = 2 * np.pi / 30.0
at_rest = multipliers(0.0, 30.0)[: 2 * 3]
exact = np.exp(np.r_[reduced.eigenvalues, reduced.eigenvalues.conj()] * T_check)
rest_error = max(np.min(np.abs(at_rest[:, None] - exact[None, :]), axis=1))
print(f"sigma = 0: multipliers - exp(lambda T) = {rest_error:.1e}")

sigma = 0.2
omegas = np.linspace(16.0, 40.0, 61)
largest = np.array([multipliers(sigma, w)[0] for w in omegas])


def margin(omega: float, sigma: float = sigma) -> float:
    """log of the largest modulus (> 0: the straight pipe is unstable)."""
    return float(np.log(np.abs(multipliers(sigma, omega)[0])))


unstable = np.flatnonzero(np.abs(largest) > 1)
edges = [
    brentq(margin, omegas[unstable[0] - 1], omegas[unstable[0]], xtol=1e-10),
    brentq(margin, omegas[unstable[-1]], omegas[unstable[-1] + 1], xtol=1e-10),
]
edge_rho = [multipliers(sigma, w)[0] for w in edges]
print(
    f"sigma = {sigma}: unstable for {edges[0]:.4f} < omega < {edges[1]:.4f}; "
    f"the multiplier at the edges {edge_rho[0].real:.6f}, {edge_rho[1].real:.6f}"
)

fig, ax = plt.subplots(figsize=(5, 3.2), layout="constrained")
real = np.abs(largest.imag) < 1e-9
ax.plot(omegas, np.abs(largest), "-", color="0.6", lw=0.8)
ax.plot(omegas[real], np.abs(largest[real]), "o", ms=3, label="real, negative")
ax.plot(omegas[~real], np.abs(largest[~real]), "s", ms=3, mfc="none", label="complex pair")
ax.axhline(1.0, color="k", lw=0.6)
ax.axvline(2 * omega_2, color="tab:red", ls=":", label="2 omega_2")
ax.set_xlabel("pulsation frequency omega")
ax.set_ylabel("largest |rho|")
ax.set_title(f"beta = 0.2, gamma = 10, mu = 0.005, v0 = {v0:g}, sigma = {sigma}, P3:6", fontsize=9)
ax.legend(fontsize=8)

# %%
# 3. The chart: a region's threshold and boundary
# -----------------------------------------------
# :func:`~fempipe.analyses.parametric.compute_parametric_chart` lists the candidate
# resonances of the mean flow's frequencies in a band (principal, omega near 2 omega_k / n,
# and combinations, omega near (omega_j +- omega_k) / n, n up to ``max_order``), and for each
# that opens finds its threshold, the least sigma at which the largest multiplier reaches
# modulus 1 (a minimum over omega of the critical sigma, by Brent's methods), and its edges at
# each requested sigma.  With damping a region opens at a finite amplitude.
sigmas = (0.1, 0.15, 0.2, 0.25, 0.3)
chart = compute_parametric_chart(model, v0, (20.0, 40.0), sigmas, max_order=1)
(region,) = chart.regions
print(
    f"region of mode {region.candidate.mode[0]} ({region.candidate.kind}): opens at "
    f"sigma = {region.sigma_threshold:.7f}, omega = {region.omega_threshold:.4f}, "
    f"multiplier {region.multiplier.real:.6f}"
)
for s, lo, hi in region.boundary:
    print(f"  sigma = {s:.2f}: {lo:.4f} < omega < {hi:.4f}")
print("closed:", ", ".join(f"{c.kind} {c.mode} near {c.omega:.2f}" for c in chart.closed))

fig, ax = plt.subplots(figsize=(5, 3.4), layout="constrained")
rows = np.array(region.boundary)
outline_w = np.r_[rows[::-1, 1], region.omega_threshold, rows[:, 2]]
outline_s = np.r_[rows[::-1, 0], region.sigma_threshold, rows[:, 0]]
ax.fill(outline_w, outline_s, color="tab:red", alpha=0.35, lw=0, label="unstable")
ax.plot(region.omega_threshold, region.sigma_threshold, "k*", ms=8, label="threshold")
ax.plot(edges, [sigma, sigma], "k|", ms=10, label="section 2's edges")
for k, w in zip(chart.modes, chart.frequencies, strict=True):
    for n in (1, 2, 3):
        if 8.0 < 2 * w / n < 42.0:
            ax.axvline(2 * w / n, color="0.5", lw=0.8, ls=":")
            ax.text(2 * w / n, 0.33, f"2ω{k}/{n}", fontsize=7, ha="center")
ax.set_xlim(8.0, 42.0)
ax.set_ylim(0.0, 0.35)
ax.set_xlabel("pulsation frequency omega")
ax.set_ylabel("pulsation amplitude sigma")
ax.set_title(f"beta = 0.2, gamma = 10, mu = 0.005, v0 = {v0:g}, P3:6", fontsize=9)
ax.legend(fontsize=7, loc="lower left")

# %%
# 4. Two independent checks
# -------------------------
# **Hill's method.** On the Ritz basis the first-order system is x' = A(tau) x with
# A = F0 + v F1 + v^2 F2 + v' F3 (``reduced.F``); with v = v0 (1 + sigma sin(omega tau)),
# A has the Fourier coefficients A_k, k = -2 to 2.  A Floquet solution
# :math:`x = e^{\lambda\tau} \sum_n c_n e^{i n \omega \tau}` makes
#
# .. math::
#
#    (\lambda + i n \omega)\, c_n = \sum_m A_{n-m}\, c_m ,
#
# an eigenproblem for lambda once truncated at :math:`|n| \le N`.  Each exponent appears
# once per harmonic, shifted by i k omega, all giving the same multiplier
# :math:`e^{\lambda T}`: keep the copy in the central strip
# :math:`|\operatorname{Im}\lambda| \le \omega/2` (a little wider: a multiplier -1 sits on its
# edge).  No time stepping: a check that shares no code with the monodromy.


def hill_exponents(F: np.ndarray, v0: float, sigma: float, omega: float, N: int) -> np.ndarray:
    """The eigenvalues of Hill's matrix truncated at |n| <= N in the central strip."""
    dim = F.shape[-1]
    sin1 = v0 * sigma * F[1] + 2 * v0**2 * sigma * F[2]  # the sin(omega tau) part of A
    cos1 = v0 * sigma * omega * F[3]  # from v' = v0 sigma omega cos(omega tau)
    cos2 = -0.5 * v0**2 * sigma**2 * F[2]  # from sin^2 = (1 - cos 2 omega tau) / 2
    coef = {
        0: F[0] + v0 * F[1] + v0**2 * (1 + 0.5 * sigma**2) * F[2],
        1: 0.5 * cos1 - 0.5j * sin1,
        -1: 0.5 * cos1 + 0.5j * sin1,
        2: 0.5 * cos2,
        -2: 0.5 * cos2,
    }
    orders = np.arange(-N, N + 1)
    H = np.zeros((orders.size * dim, orders.size * dim), dtype=complex)
    for i, n in enumerate(orders):
        for j, m in enumerate(orders):
            if abs(n - m) <= 2:
                H[i * dim : (i + 1) * dim, j * dim : (j + 1) * dim] = coef[n - m]
        H[i * dim : (i + 1) * dim, i * dim : (i + 1) * dim] -= 1j * n * omega * np.eye(dim)
    lam = np.linalg.eigvals(H)
    return lam[np.abs(lam.imag) <= 0.51 * omega]


omega_in = 29.5
T_in = 2 * np.pi / omega_in
rho_in = multipliers(sigma, omega_in, steps=1024)[0]
with single_blas_thread():
    hill_errors = {}
    for N in (1, 2, 3, 4, 6, 8):
        lam = hill_exponents(reduced.F, v0, sigma, omega_in, N)
        hill_errors[N] = abs(np.exp(lam[np.argmax(lam.real)] * T_in) - rho_in)
print(f"sigma = {sigma}, omega = {omega_in}: monodromy (1024 steps) rho = {rho_in.real:.10f}")
for N, err in hill_errors.items():
    print(f"  Hill, |n| <= {N}: |rho_Hill - rho| = {err:.1e}")

# %%
# **Eq. (20) with the pulsating flow.** The nonlinear model, not its linearization: a small
# perturbation in the second mode (1e-5), integrated by :func:`fempipe.simulate` with
# ``flow=PulsatingFlow(v0, sigma, omega)`` for twelve periods, inside the region
# (omega = 29.5) and outside it (omega = 22).  Inside, the tip angle changes per period by the
# largest multiplier, sign included: the motion has the period 2T.
q0, qd0 = fempipe.make_initial_state(model, mode=2, amplitude=1e-5)
periods, per_period = 12, 16
fig, ax = plt.subplots(figsize=(5, 3.2), layout="constrained")
for omega, colour in ((omega_in, "tab:red"), (22.0, "tab:blue")):
    T = 2 * np.pi / omega
    flow = fempipe.PulsatingFlow(v0, sigma, omega)
    run = fempipe.simulate(
        model, q0, qd0, periods * T, rtol=1e-8, flow=flow, n_out=periods * per_period + 1
    )
    tip = run.q @ model.disc.tip  # theta(1, tau)
    rho_max = multipliers(sigma, omega)[0]
    ax.semilogy(run.t / T, np.abs(tip), color=colour, lw=0.8, label=f"omega = {omega:g}")
    ax.semilogy(
        run.t / T, np.abs(tip[0]) * np.abs(rho_max) ** (run.t / T), "--", color=colour, lw=0.8
    )
    if omega == omega_in:
        at_periods = tip[::per_period]
        sim_ratio = at_periods[-1] / at_periods[-2]
        print(
            f"omega = {omega:g}: theta_tip(12T) / theta_tip(11T) = {sim_ratio:.6f}, "
            f"largest multiplier {rho_max.real:.6f}"
        )
    else:
        decay = abs(tip[-1] / tip[0])
        print(f"omega = {omega:g}: |rho| = {abs(rho_max):.4f}, |theta_tip| fell by {decay:.1e}")
ax.set_xlabel("tau / T")
ax.set_ylabel("|theta(1)|")
ax.set_title(f"Eq. (20), v0 = {v0:g}, sigma = {sigma}, P3:6; dashed: |rho|^(tau/T)", fontsize=9)
ax.legend(fontsize=8)
show_or_save()  # run as a script: a window, or PNG files without a display

# %%
# Exercises
# ---------
# ``check("8.k", answer)`` compares an answer with a reference computed independently (other
# integrators, a finer mesh).  Each solution runs in this lesson.
#
# 1. The damped Mathieu equation with c = 0.1 at delta = 1/4, eps = 0.4: compute the
#    multiplier of largest modulus.  Compare with averaging's estimate
#    :math:`-e^{(\varepsilon - c) \pi}`.
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    Inside the tongue the two multipliers are real and negative; their product is
#    exp(-0.2 pi).  Averaging holds for small eps only and overestimates.
#    Expected: ``answer`` = -2.3770042 (averaging: ``estimate`` = -2.566).
#
#    .. code-block:: python
#
#       rho_1 = np.linalg.eigvals(mathieu_monodromy(0.25, 0.4, 0.1))
#       answer = rho_1[np.argmax(np.abs(rho_1))].real
#       estimate = -np.exp((0.4 - 0.1) * np.pi)
#       print(f"rho = {answer:.7f}, averaging {estimate:.3f}")
#       check("8.1", answer)
#
#    .. raw:: html
#
#       </details>
#
# 2. The threshold of the region at v0 = 6, by hand: the critical amplitude sigma_c(omega)
#    at which the largest multiplier has modulus 1 (``brentq`` on section 2's ``margin``),
#    then its minimum over omega (``minimize_scalar``).
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    sigma_c is flat at its minimum: an error of 1e-3 in omega costs sigma 1e-8 or less.
#    P3:6 differs from the finer mesh of the reference by 1.3e-6.
#    Expected: ``answer`` = 0.0883045 at ``omega_th`` = 29.47.
#
#    .. code-block:: python
#
#       from scipy.optimize import minimize_scalar
#
#       def sigma_c(omega):
#           return brentq(lambda s: margin(omega, s), 0.05, 0.2, xtol=1e-11)
#
#       best = minimize_scalar(
#           sigma_c, bounds=(28.0, 31.0), method="bounded", options={"xatol": 1e-3}
#       )
#       answer, omega_th = best.fun, best.x
#       print(f"sigma_th = {answer:.7f} at omega = {omega_th:.3f}")
#       check("8.2", answer)
#
#    .. raw:: html
#
#       </details>
#
# 3. Just outside the boundary at sigma = 0.3 (section 3: the region starts at 22.51),
#    compute the largest multiplier at omega = 21 by Hill's method with 8 harmonics.  Is
#    the straight pipe stable there?
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    Stable: the multiplier is real, negative and inside the unit circle (the region's
#    -1 lies further in).  Expected: ``answer`` = -0.5865056.
#
#    .. code-block:: python
#
#       lam_21 = hill_exponents(reduced.F, v0, 0.3, 21.0, 8)
#       answer = np.exp(lam_21[np.argmax(lam_21.real)] * 2 * np.pi / 21.0).real
#       print(f"Hill: rho = {answer:.7f}")
#       check("8.3", answer)
#
#    .. raw:: html
#
#       </details>
