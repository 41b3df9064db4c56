"""The pipe in three dimensions: the geometrically exact weak form, one method per term.

The planar model (Eq. (20), :mod:`fempipe.model.weak_form`) holds for motion
in the plane of the clamp and gravity.  A round pipe may leave that plane;
this module is the same pipe in space, under the same assumptions
(inextensible, isotropic section, no twist, the same fluid terms, gravity,
Kelvin-Voigt damping made objective, the end mass and external damping), on
the same discretizations.  The tangent t(xi, tau) is the unknown, through the
singularity-free chart of :mod:`fempipe.model.space_chart` with three fields
u = (theta, a, b), stacked as U = (theta_dofs, a_dofs, b_dofs).

The weak form
-------------
The virtual work of Eq. (20) written with vectors: for a variation delta u
(the test functions phi_i on each field) the tangent varies by
delta t = J delta u (J = dt/du) and the centerline by
delta r = \\int_0^xi delta t.  Every force per unit length f(xi) then does the
work ``\\int delta r . f = \\int delta t . C^R f`` (C^R the integral to the
free end, :mod:`fempipe.model.quadrature`), so each term is a vector field G
tested as ``\\int phi_i J_c . G``:

=====================  ===================================================
inertia                ``C^R C t_ddot`` (with its centripetal part)
coriolis               ``2 v sqrt(beta) C^R t_dot``
flow_acceleration      ``v_dot sqrt(beta) C^R t``
follower               ``v^2 t(1)``
gravity                ``-gamma (1 - xi + Gamma) g``, g = (cos alpha, -sin alpha, 0)
end_mass_inertia       ``Gamma r_ddot(1)``, r_ddot(1) = \\int_0^1 t_ddot
external_damping       ``sigma C^R C t_dot``
=====================  ===================================================

In the plane J_theta = n, t_ddot = theta_ddot n - theta_dot^2 t, and each row is
the planar term of the same name (n . g = -sin(theta + alpha),
n . t(1) = sin(theta(1) - theta)).  Two terms act on the curvature:

* **bending**: the energy (1/2) \\int |t'|^2 (EI = 1), whose variation is
  ``\\int t' . (dt'/du_c phi_i + J_c phi_i')`` (= \\int theta' phi_i' in the
  plane);
* **kelvin_voigt**, objective: the dissipation (mu/2) \\int |k|^2 of the
  co-rotational rate of the curvature vector t x t', which for a section
  frame without twist is k = omega', the xi-derivative of the frame's
  angular velocity omega = t x t_dot + Omega t.  The compatibility of the
  frame (d_xi of its angular velocity minus d_tau of its curvature equals
  their cross product) and zero twist give
  ``k = t x t_dot' + Omega t'``, ``Omega = \\int_0^xi t' . (t x t_dot)``
  (the spin about the tangent that the frame acquires when a curved pipe
  moves out of its plane).  Its variation with respect to u_dot is
  ``mu \\int [delta t_dot' . (k x t) + delta t_dot . (t' x t) C^R(k . t')]``.
  In the plane k = theta_dot' e_3: the planar mu K q'.  Linearized about a
  planar state it is the out-of-plane model's damping
  (:mod:`fempipe.model.out_of_plane`).

The gauge
---------
Three fields describe two degrees of freedom: along the fiber f(u) the
tangent does not move (:mod:`fempipe.model.space_chart`).  The term
``gauge`` gives that direction an equation of its own,

    r_g = d/dtau (f . u_dot) + c_g f . u_dot + k_g f . (0, a, b) = 0,

tested with ``f . delta u``: a damped oscillator pulling the coordinates to
the least |(a, b)| on each fiber.  It does not act on the physics in the
continuum (a test in the physical directions has f . delta u = 0, a test
along f sees no physical force), it is zero at every planar state
(so the planar equations are exactly those of the planar model), and it
makes the mass matrix definite.

The Jacobians of every term are exact: the weak form is evaluated on
:class:`~fempipe.core.dual.Dual` fields seeded with the derivatives of u,
u_dot and u_ddot with respect to U, U_dot and U_ddot.
"""

from __future__ import annotations

import weakref

import numpy as np
import scipy.linalg as sla

from ..core.dual import Dual, cross, dot, stack
from .discretization import Discretization
from .params import Params
from .space_chart import SpaceFields, space_fields, tangent

__all__ = ["GAUGE_DAMPING", "GAUGE_STIFFNESS", "SpaceModel", "planar_state", "plane_of"]

#: c_g and k_g of the gauge equation: the gauge relaxes with the rates 50 and 100 (roots of
#: s^2 + c_g s + k_g), so that its Floquet multipliers (e^(-50 T) and below) lie far
#: inside those of the physics (:mod:`fempipe.analyses.space.floquet`).
GAUGE_DAMPING = 150.0
GAUGE_STIFFNESS = 5000.0

_SEEDS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _dense(A) -> np.ndarray:
    return A.toarray() if hasattr(A, "toarray") else np.asarray(A, dtype=float)


#: The pointwise quantities the local derivatives are taken with respect to, in
#: order (3 components each): (field, basis, block of unknowns).
_KINDS = (
    ("u", "Phi", "q"),
    ("u_prime", "dPhi", "q"),
    ("u_dot", "Phi", "qdot"),
    ("u_dot_prime", "dPhi", "qdot"),
    ("u_ddot", "Phi", "qddot"),
)


class _Seeds:
    """Phi, dPhi, tip of a discretization (dense), for the Dual fields."""

    def __init__(self, disc: Discretization) -> None:
        self.Phi = _dense(disc.Phi)
        self.dPhi = _dense(disc.dPhi)
        self.tip = np.asarray(disc.tip, dtype=float)

    @classmethod
    def of(cls, disc: Discretization) -> _Seeds:
        s = _SEEDS.get(disc)
        if s is None:
            s = _SEEDS[disc] = cls(disc)
        return s


class _Blocks:
    """The unknowns a Jacobian is taken with respect to, and the maps of the derivatives.

    Pointwise quantities carry derivatives with respect to the 15 local values
    (u, u', u_dot, u_dot', u_ddot at their own point, :data:`_KINDS`);
    :meth:`expand` turns them into derivatives with respect to the unknowns
    (``len(blocks) n`` directions) where an integral mixes the points, and
    :meth:`assemble_local` tests them (the Jacobian of a local term is a sum of
    ``Phi^T diag(d) Phi``-like products).
    """

    def __init__(self, seeds: _Seeds, blocks: tuple[str, ...]) -> None:
        self.seeds = seeds
        self.blocks = blocks
        self.nt = seeds.Phi.shape[1]
        self.N = 3 * self.nt
        self.K = len(blocks) * self.N
        self.kinds = [
            (k, getattr(seeds, basis), blocks.index(block) * self.N)
            for k, (_f, basis, block) in enumerate(_KINDS)
            if block in blocks
        ]

    def expand(self, loc: np.ndarray) -> np.ndarray:
        n_q = loc.shape[0]
        L = loc.reshape(n_q, -1, len(_KINDS), 3)
        out = np.zeros((n_q, L.shape[1], self.K))
        for k, B, off in self.kinds:
            part = L[:, :, k, :, None] * B[:, None, None, :]  # (n_q, r, 3, nt)
            out[:, :, off : off + self.N] += part.reshape(n_q, L.shape[1], self.N)
        return out.reshape(loc.shape[:-1] + (self.K,))

    def assemble_local(self, loc: np.ndarray, test: np.ndarray, w: np.ndarray, J) -> None:
        r"""Add ``\int test_i loc_(c, l) (local basis)_j`` to the Jacobian J (3 nt, K)."""
        nt, n_q = self.nt, loc.shape[0]
        L = loc.reshape(n_q, 3, len(_KINDS), 3) * w[:, None, None, None]
        testT = np.ascontiguousarray(test.T)
        for k, B, off in self.kinds:
            Lk = L[:, :, k, :].reshape(n_q, 9)
            # T[m, i, j] = sum_q test_qi L_qm B_qj, m = (c, c')
            T = np.matmul(testT[None], Lk.T[:, :, None] * B[None])  # (9, nt, nt)
            T = T.reshape(3, 3, nt, nt).transpose(0, 2, 1, 3).reshape(self.N, self.N)
            J[:, off : off + self.N] += T


def planar_state(q: np.ndarray) -> np.ndarray:
    """The 3-D state U = (q, 0, 0) of a planar state q (the exact planar reduction)."""
    q = np.asarray(q, dtype=float)
    return np.concatenate([q, np.zeros(2 * q.size)])


def plane_of(U: np.ndarray) -> np.ndarray:
    """The theta part of a 3-D state: the planar state when a = b = 0."""
    U = np.asarray(U)
    return U[: U.size // 3].copy()


class SpaceModel:
    """The residual of the 3-D weak form and its exact Jacobians (module docstring).

    Parameters
    ----------
    disc : Discretization
        The discretization of each of the three fields (as the planar model's
        theta).
    params : Params
        Dimensionless parameters.  Springs and hysteretic damping are refused:
        the springs have no 3-D term yet, hysteretic damping no time-domain
        meaning.

    Attributes
    ----------
    n : int
        ``3 disc.n`` unknowns.
    """

    gauge_damping = GAUGE_DAMPING
    gauge_stiffness = GAUGE_STIFFNESS

    def __init__(self, disc: Discretization, params: Params) -> None:
        if params.springs:
            raise ValueError(
                "the 3-D model has no spring term: springs = () is required "
                f"(got springs = {params.springs!r})"
            )
        if params.hysteretic_damping:
            raise ValueError(
                "the 3-D model integrates in time: hysteretic damping (mu_h = "
                f"{params.hysteretic_damping:g}) has no time-domain meaning; set it to 0"
            )
        self.disc = disc
        self.params = params
        self.quad = disc.quad
        self.x = disc.quad.x
        self.w = disc.quad.w
        self.n_theta = disc.n
        self.n = 3 * disc.n
        self._seeds = _Seeds.of(disc)
        self._maps: _Blocks | None = None
        # Phi^T W and dPhi^T W: the test integrals of the two parts of the weak form.
        self._tests = tuple(
            np.ascontiguousarray((B * self.w[:, None]).T)
            for B in (self._seeds.Phi, self._seeds.dPhi)
        )

    def with_params(self, params: Params) -> SpaceModel:
        """The model on the same discretization with other parameters."""
        return SpaceModel(self.disc, params)

    @property
    def gravity_direction(self) -> np.ndarray:
        """g = (cos alpha, -sin alpha, 0) in the pipe's frame: t . g = cos(theta + alpha)."""
        a = self.params.alpha
        return np.array([np.cos(a), -np.sin(a), 0.0])

    # ------------------------------------------------------- fields --
    def fields(self, U, Ud=None, Udd=None, blocks: tuple[str, ...] = ()) -> SpaceFields:
        """The kinematics at the quadrature points, with derivatives along ``blocks``.

        U, Ud, Udd have shape (3 n,) or (S, 3 n) (S states at once); the
        fields have a last axis of length S.  ``blocks`` names the unknowns to
        differentiate with respect to (one state only), in order, among
        ``"q"`` (U), ``"qdot"`` (U_dot) and ``"qddot"`` (U_ddot).
        """
        s = self._seeds
        nt = self.n_theta
        U = np.atleast_2d(np.asarray(U, dtype=float))
        S = U.shape[0]
        zero = np.zeros_like(U)
        Ud = zero if Ud is None else np.atleast_2d(np.asarray(Ud, dtype=float))
        Udd = zero if Udd is None else np.atleast_2d(np.asarray(Udd, dtype=float))
        if blocks and S != 1:
            raise ValueError("derivatives are taken for one state at a time")
        maps = _Blocks(s, blocks) if blocks else None
        values = {"u": U, "u_prime": U, "u_dot": Ud, "u_dot_prime": Ud, "u_ddot": Udd}
        out = {}
        for k, (name, basis, block) in enumerate(_KINDS):
            val = np.einsum("qj,scj->qcs", getattr(s, basis), values[name].reshape(S, 3, nt))
            loc = None
            if maps is not None and block in blocks:
                loc = np.zeros(val.shape + (3 * len(_KINDS),))
                for c in range(3):
                    loc[:, c, :, 3 * k + c] = 1.0
            out[name] = val if maps is None else Dual(val, None, loc)
        tip_val = np.einsum("j,scj->cs", s.tip, U.reshape(S, 3, nt))[None]
        tip_der = None
        if maps is not None and "q" in blocks:
            tip_der = np.zeros(tip_val.shape + (maps.K,))
            off = blocks.index("q") * self.n
            for c in range(3):
                tip_der[0, c, 0, off + c * nt : off + (c + 1) * nt] = s.tip
        self._maps = maps
        return space_fields(
            out["u"],
            out["u_dot"],
            out["u_ddot"],
            out["u_prime"],
            out["u_dot_prime"],
            tip_val if maps is None else Dual(tip_val, tip_der),
        )

    def _integral(self, x: Dual, op) -> Dual:
        """A linear map mixing the points (an integration operator) of x."""
        if not isinstance(x, Dual):
            return op(x)
        maps = self._maps
        return x.nonlocal_map(op, None if maps is None else maps.expand)

    # ------------------------------------------- the terms: force fields G --
    def inertia(self, fl: SpaceFields) -> Dual:
        """``C^R C t_ddot``: the pipe's inertia force beyond xi, centripetal part included."""
        return self._integral(
            self._integral(fl.t_ddot, self.quad.cumulative_cells), self.quad.from_tip_cells
        )

    def coriolis(self, fl: SpaceFields) -> Dual:
        """``2 v sqrt(beta) C^R t_dot``."""
        p = self.params
        return (2.0 * p.v * np.sqrt(p.beta)) * self._integral(fl.t_dot, self.quad.from_tip_cells)

    def flow_acceleration(self, fl: SpaceFields, v_dot: float) -> Dual | None:
        """``v_dot sqrt(beta) C^R t`` (unsteady flow)."""
        if not v_dot:
            return None
        return (v_dot * np.sqrt(self.params.beta)) * self._integral(fl.t, self.quad.from_tip_cells)

    def follower(self, fl: SpaceFields) -> Dual:
        """``v^2 t(1)``: the jet's reaction and the fluid's centrifugal force, Eq. (14)."""
        v = self.params.v
        return (v * v) * fl.t_tip

    def gravity(self) -> np.ndarray:
        """``-gamma (1 - xi + Gamma) g``: the weight of the pipe and of the end mass beyond xi."""
        p = self.params
        lever = 1.0 - self.x + p.end_mass
        return -p.gamma * lever[:, None, None] * self.gravity_direction[None, :, None]

    def end_mass_inertia(self, fl: SpaceFields) -> Dual | None:
        """``Gamma r_ddot(1)``: the end mass's inertia, felt by every section."""
        G = self.params.end_mass
        if not G:
            return None
        acc = self._integral(fl.t_ddot, self.quad.integrate)  # (3, S)
        return G * acc[None]

    def external_damping(self, fl: SpaceFields) -> Dual | None:
        """``sigma C^R C t_dot``: a viscous force -sigma r_dot along the pipe."""
        sigma = self.params.external_damping
        if not sigma:
            return None
        rdot = self._integral(fl.t_dot, self.quad.cumulative_cells)
        return sigma * self._integral(rdot, self.quad.from_tip_cells)

    def bending(self, fl: SpaceFields) -> tuple[Dual, Dual]:
        """(A, B): the variation of ``(1/2) \\int |t'|^2`` is ``\\int A_c phi_i + B_c phi_i'``."""
        tp = fl.t_prime
        A = stack([dot(tp, fl.dt_prime[c]) for c in range(3)], axis=1)
        B = stack([dot(tp, fl.J[c]) for c in range(3)], axis=1)
        return A, B

    def curvature_rate(self, fl: SpaceFields) -> Dual:
        """k = t x t_dot' + Omega t': the co-rotational rate of the curvature vector."""
        Omega = self._integral(dot(fl.t_prime, cross(fl.t, fl.t_dot)), self.quad.cumulative_cells)
        return cross(fl.t, fl.t_dot_prime) + fl.t_prime * Omega[:, None]

    def kelvin_voigt(self, fl: SpaceFields) -> tuple[Dual, Dual] | None:
        """(A, B) of the objective Kelvin-Voigt damping (module docstring)."""
        mu = self.params.mu
        if not mu:
            return None
        k = self.curvature_rate(fl)
        kxt = cross(k, fl.t)
        tail = self._integral(dot(k, fl.t_prime), self.quad.from_tip_cells)
        tpxt = cross(fl.t_prime, fl.t) * tail[:, None]
        A = stack([dot(fl.dt_prime[c], kxt) + dot(fl.J[c], tpxt) for c in range(3)], axis=1)
        B = stack([dot(fl.J[c], kxt) for c in range(3)], axis=1)
        return mu * A, mu * B

    def gauge(self, fl: SpaceFields) -> Dual:
        """A of the gauge term: ``r_g f_c`` (module docstring)."""
        f, u = fl.fiber, fl.u
        rate = dot(f, fl.u_dot)
        r = (
            dot(f, fl.u_ddot)
            + dot(fl.fiber_dot, fl.u_dot)
            + self.gauge_damping * rate
            + self.gauge_stiffness * (f[:, 1] * u[:, 1] + f[:, 2] * u[:, 2])
        )
        return f * r[:, None]

    # ------------------------------------------------------- totals --
    def force_field(self, fl: SpaceFields, v_dot: float = 0.0) -> Dual:
        """The sum G of the force fields of all terms tested as ``\\int delta t . G``."""
        G = self.inertia(fl) + self.coriolis(fl) + self.follower(fl) + self.gravity()
        for extra in (
            self.flow_acceleration(fl, v_dot),
            self.end_mass_inertia(fl),
            self.external_damping(fl),
        ):
            if extra is not None:
                G = G + extra
        return G

    def _weak_form(self, fl: SpaceFields, v_dot: float) -> Dual:
        """The residual (and its derivatives) as a Dual of shape (n,)."""
        G = self.force_field(fl, v_dot)
        A, B = self.bending(fl)
        A = A + stack([dot(fl.J[c], G) for c in range(3)], axis=1) + self.gauge(fl)
        kv = self.kelvin_voigt(fl)
        if kv is not None:
            A, B = A + kv[0], B + kv[1]
        s = self._seeds
        tests = self._tests

        def assemble(a, b):
            # (n_q, 3, S, ...) -> (3, n, S, ...) -> (3 n, S, ...); None: no dependence
            r = 0.0
            for x, T in ((a, tests[0]), (b, tests[1])):
                if x is not None:
                    r = r + (T @ x.reshape(x.shape[0], -1)).reshape((T.shape[0],) + x.shape[1:])
            r = np.moveaxis(r, 0, 1)
            return r.reshape((self.n,) + r.shape[2:])

        maps = self._maps
        if maps is None:
            return Dual(assemble(A, B).T)  # (S, 3 n)
        val = assemble(A.val, B.val).T
        der = assemble(A.der, B.der)
        der = np.zeros((self.n, maps.K)) if np.isscalar(der) else der[:, 0]
        for x, basis in ((A, s.Phi), (B, s.dPhi)):
            if x.loc is not None:
                maps.assemble_local(x.loc[:, :, 0], basis, self.w, der)
        return Dual(val[0], der)

    def residual(self, U, Ud=None, Udd=None, v_dot: float = 0.0) -> np.ndarray:
        """R(U, U', U''), shape (3 n,); for S states (rows of (S, 3 n) arrays), (S, 3 n)."""
        r = self._weak_form(self.fields(U, Ud, Udd), v_dot).val
        return r if np.ndim(U) == 2 else r[0]

    def jacobians(self, U, Ud=None, Udd=None, v_dot: float = 0.0):
        """Exact ``(dR/dU, dR/dU', dR/dU'')``, dense (3 n, 3 n) each; dR/dU'' symmetrized."""
        fl = self.fields(U, Ud, Udd, blocks=("q", "qdot", "qddot"))
        D = self._weak_form(fl, v_dot).der
        n = self.n
        M = D[:, 2 * n :]
        return D[:, :n], D[:, n : 2 * n], 0.5 * (M + M.T)

    def mass_matrix(self, U) -> np.ndarray:
        """dR/dU'' (R is affine in U''), symmetric positive definite, shape (3 n, 3 n)."""
        M = self._weak_form(self.fields(U, blocks=("qddot",)), 0.0).der
        return 0.5 * (M + M.T)

    def acceleration(self, U, Ud, v_dot: float = 0.0) -> np.ndarray:
        """U'' from R = 0: ``M U'' = -R(U, U', 0)``."""
        M = self.mass_matrix(U)
        return -sla.cho_solve(sla.cho_factor(M), self.residual(U, Ud, None, v_dot))

    # ------------------------------------------------------ geometry --
    def centerline_velocity(self, fl: SpaceFields) -> np.ndarray:
        """r_dot = C t_dot at the quadrature points, shape (n_q, 3)."""
        return self.quad.cumulative(fl.t_dot[:, :, 0])

    def tip_tangent(self, U) -> np.ndarray:
        """t(1), shape (3,)."""
        u1 = self._seeds.tip @ np.asarray(U).reshape(3, self.n_theta).T
        return tangent(u1[None, :, None])[0, :, 0]

    def centerline(self, U) -> np.ndarray:
        """r(xi) = \\int_0^xi t at the cell edges, shape (n_cells + 1, 3), in the pipe's frame."""
        return self.quad.at_edges(self.fields(U).t[:, :, 0])

    def tip_position_gradient(self, U) -> np.ndarray:
        """d r(1) / dU in the pipe's frame, shape (3, 3 n): r(1) = \\int_0^1 t."""
        fl = self.fields(U, blocks=("q",))
        der = self._maps.expand(fl.t.loc)[:, :, 0, :]  # (n_q, 3, 3 n)
        return np.tensordot(self.w, der, axes=(0, 0))

    def tip_coordinates(self, U) -> dict:
        """The tip in the frames of the files: eta_tip (in the pipe's frame, e_2), X_tip (along
        gravity), Z_tip (horizontal, in the plane of the static state) and Y_tip (out of it).

        Floats for one state U (3 n,), arrays (S,) for S states (S, 3 n).  For a planar
        state they are those of :func:`fempipe.model.kinematics.tip_values`.
        """
        t = self.fields(U).t  # (n_q, 3, S)
        r1 = np.tensordot(self.w, t, axes=(0, 0))  # (3, S)
        a = self.params.alpha
        out = {
            "eta_tip": r1[1],
            "X_tip": np.cos(a) * r1[0] - np.sin(a) * r1[1],
            "Z_tip": np.sin(a) * r1[0] + np.cos(a) * r1[1],
            "Y_tip": r1[2],
        }
        if np.ndim(U) == 1:
            return {k: float(v[0]) for k, v in out.items()}
        return out

    # ------------------------------------------------------- energy --
    def kinetic_energy(self, U, Ud) -> float:
        """``T = (1/2) \\int |r_dot|^2 + (Gamma/2) |r_dot(1)|^2``."""
        fl = self.fields(U, Ud)
        rd = self.centerline_velocity(fl)
        T = 0.5 * float(self.w @ np.einsum("qc,qc->q", rd, rd))
        G = self.params.end_mass
        if G:
            tip = self.quad.integrate(fl.t_dot[:, :, 0])
            T += 0.5 * G * float(tip @ tip)
        return T

    def potential_energy(self, U) -> float:
        """Bending and gravity: ``(1/2) \\int |t'|^2 + gamma [cos(alpha)/2 - \\int (1 - xi) t . g]
        + gamma Gamma [cos(alpha) - \\int t . g]`` (zero for the straight pipe, as in the plane)."""
        fl = self.fields(U)
        p = self.params
        tp = fl.t_prime[:, :, 0]
        tg = fl.t[:, :, 0] @ self.gravity_direction
        V = 0.5 * float(self.w @ np.einsum("qc,qc->q", tp, tp))
        grav = 0.5 * np.cos(p.alpha) - self.w @ ((1.0 - self.x) * tg)
        if p.end_mass:
            grav = grav + p.end_mass * (np.cos(p.alpha) - self.w @ tg)
        return V + p.gamma * float(grav)

    def power_terms(self, U, Ud, Udd, v_dot: float = 0.0) -> dict:
        r"""The power of each non-conservative term: dE/dtau = -sum of the values.

        The virtual power of a term for the test U' (``U' . R_term``): for a
        force field G it is ``\int t_dot . G``.  Keys: ``coriolis``
        (``2 v sqrt(beta) \int t_dot . C^R t_dot = v sqrt(beta) |r_dot(1)|^2 >= 0``,
        the momentum the fluid carries out), ``follower`` (``v^2 r_dot(1) . t(1)``),
        ``kelvin_voigt`` (``mu \int |k|^2 >= 0``), ``external_damping``
        (``sigma \int |r_dot|^2``), ``flow_acceleration`` and ``gauge``: the work of
        the gauge term, zero in the continuum and at planar states, a
        discretization error elsewhere (it falls as h^7 on P3 elements, measured).
        """
        fl = self.fields(U, Ud, Udd)
        w = self.w
        td = fl.t_dot

        def field_power(G) -> float:
            return (
                0.0
                if G is None
                else float(w @ np.einsum("qcs,qcs->q", td, np.asarray(G) * np.ones_like(td)))
            )

        out = {
            "coriolis": field_power(self.coriolis(fl)),
            "follower": field_power(self.follower(fl)),
            "external_damping": field_power(self.external_damping(fl)),
            "flow_acceleration": field_power(self.flow_acceleration(fl, v_dot)),
        }
        kv = self.kelvin_voigt(fl)
        out["kelvin_voigt"] = 0.0
        if kv is not None:
            out["kelvin_voigt"] = float(
                w
                @ (
                    np.einsum("qcs,qcs->q", kv[0], fl.u_dot)
                    + np.einsum("qcs,qcs->q", kv[1], fl.u_dot_prime)
                )
            )
        out["gauge"] = float(w @ np.einsum("qcs,qcs->q", self.gauge(fl), fl.u_dot))
        return out

    def energy(self, U, Ud) -> float:
        """E = T + V: conserved for v = 0, mu = 0, sigma = 0 (up to the gauge's work)."""
        return self.kinetic_energy(U, Ud) + self.potential_energy(U)

    def dynamics_problem(self, flow=None):
        """The integrator's problem of this model (:class:`fempipe.model.space_dynamics.SpaceDynamics`)."""
        from .space_dynamics import SpaceDynamics

        return SpaceDynamics(self, flow)
