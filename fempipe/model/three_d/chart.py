"""The tangent of the pipe in space from three fields, free of coordinate singularities.

The unknowns u = (theta, a, b), each discretized like theta, give the tangent as the image
of e_1 under the unnormalized quaternion (cos(theta/2), a, b, sin(theta/2)):
t = (cos theta + a^2 - b^2, sin theta + 2 a b, 2 (a s - b c)) / (1 + a^2 + b^2), the planar
tangent for a = b = 0.  The map has rank 2 everywhere; t does not change along the fiber
(:func:`fiber_direction`).  :func:`compute_fields_3d` gives t and its derivatives as
:class:`~fempipe.core.dual.Dual` values.

Derivation: docs/theory/space.md, "The unknown".
"""

from __future__ import annotations

from dataclasses import dataclass

from fempipe.core.dual import Dual, cos, matvec, sin, stack

__all__ = ["Fields3D", "fiber_direction", "compute_fields_3d", "tangent"]


def _vec(x, y, z) -> Dual:
    return stack([x, y, z], axis=1)


@dataclass(frozen=True)
class _Point:
    """theta, a, b at a set of points, with the trigonometric values the chart uses."""

    th: Dual
    a: Dual
    b: Dual
    c: Dual  # cos(theta/2)
    s: Dual  # sin(theta/2)
    ct: Dual  # cos(theta)
    st: Dual  # sin(theta)

    @classmethod
    def of(cls, u: Dual) -> _Point:
        th, a, b = u[:, 0], u[:, 1], u[:, 2]
        half = th * 0.5
        return cls(th, a, b, cos(half), sin(half), cos(th), sin(th))

    def numerator(self) -> tuple[Dual, Dual]:
        """(P, D): t = P / D."""
        a, b = self.a, self.b
        P = _vec(self.ct + a * a - b * b, self.st + 2.0 * (a * b), 2.0 * (a * self.s - b * self.c))
        return P, 1.0 + a * a + b * b


def _over(x: Dual, D: Dual) -> Dual:
    return x * (1.0 / D)[:, None]


def tangent(u) -> Dual:
    """t(u) for u of shape (m, 3, ...) (axis 1: theta, a, b): the chart."""
    P, D = _Point.of(u).numerator()
    return _over(P, D)


def fiber_direction(p: _Point) -> Dual:
    """f(u): the direction of u along which t does not change (docs/theory/space.md)."""
    g = p.a * p.c + p.b * p.s
    return _vec(p.a * p.s - p.b * p.c, 0.5 * (p.c + p.a * g), 0.5 * (p.s + p.b * g))


def _fiber_rate(p: _Point, ud: Dual) -> Dual:
    """f_dot = grad f [u_dot]."""
    thd, ad, bd = ud[:, 0], ud[:, 1], ud[:, 2]
    a, b, c, s = p.a, p.b, p.c, p.s
    cd, sd = -0.5 * s * thd, 0.5 * c * thd
    g = a * c + b * s
    gd = ad * c + a * cd + bd * s + b * sd
    return _vec(
        ad * s + a * sd - bd * c - b * cd,
        0.5 * (cd + ad * g + a * gd),
        0.5 * (sd + bd * g + b * gd),
    )


@dataclass(frozen=True)
class Fields3D:
    """A 3-D state's kinematics at the quadrature points ((n_q, 3) Duals): the fields ``u...``,
    the tangent ``t...``, ``J[c] = dt/du_c``, ``dt_prime[c] = dt'/du_c``, ``fiber...``, ``t_tip``."""

    u: Dual
    u_dot: Dual
    u_ddot: Dual
    u_prime: Dual
    u_dot_prime: Dual
    t: Dual
    t_dot: Dual
    t_ddot: Dual
    t_prime: Dual
    t_dot_prime: Dual
    J: list
    dt_prime: list
    fiber: Dual
    fiber_dot: Dual
    t_tip: Dual


def _gradient(p: _Point) -> tuple:
    """(G, g): ``G[:, i, c] = dP_i/du_c`` (n, 3, 3, ...) and ``g[:, c] = dD/du_c`` (n, 3, ...)."""
    a, b, c, s = p.a, p.b, p.c, p.s
    G = stack(
        [_vec(-p.st, p.ct, a * c + b * s), 2.0 * _vec(a, b, s), 2.0 * _vec(-b, a, -c)], axis=2
    )
    return G, _vec(0.0 * a, 2.0 * a, 2.0 * b)


def _hessian(p: _Point, w) -> tuple:
    """(H, h) with hess P [v, w] = H v and hess D [v, w] = h . v."""
    wt, wa, wb = w[:, 0], w[:, 1], w[:, 2]
    c, s = p.c, p.s
    Pz4 = 0.5 * (p.a * s - p.b * c)  # P_z / 4
    H = stack(
        [
            _vec(-p.ct * wt, -p.st * wt, c * wa + s * wb - Pz4 * wt),
            _vec(2.0 * wa, 2.0 * wb, c * wt),
            _vec(-2.0 * wb, 2.0 * wa, s * wt),
        ],
        axis=2,
    )
    return H, _vec(0.0 * wa, 2.0 * wa, 2.0 * wb)


def _hessian_quadratic(p: _Point, w) -> tuple:
    """(hess P [w, w], hess D [w, w]) without forming the matrices of :func:`_hessian`."""
    wt, wa, wb = w[:, 0], w[:, 1], w[:, 2]
    Pz4 = 0.5 * (p.a * p.s - p.b * p.c)  # P_z / 4
    wt2 = wt * wt
    Hww = _vec(
        2.0 * (wa * wa - wb * wb) - p.ct * wt2,
        4.0 * (wa * wb) - p.st * wt2,
        2.0 * ((p.c * wa + p.s * wb) * wt) - Pz4 * wt2,
    )
    return Hww, 2.0 * (wa * wa + wb * wb)


def _dot(x, y):
    return (x * y).sum(axis=1)


def compute_fields_3d(u, u_dot, u_ddot, u_prime, u_dot_prime, u_tip) -> Fields3D:
    """The kinematics of :class:`Fields3D`, every derivative of t a product with the gradient and Hessian formed once."""
    p = _Point.of(u)
    P, D = p.numerator()
    inv = 1.0 / D
    t = P * inv[:, None]
    G, g = _gradient(p)
    Hp, hp = _hessian(p, u_prime)
    Hdd, hdd = _hessian_quadratic(p, u_dot)
    Dd, Dp = _dot(g, u_dot), _dot(g, u_prime)
    td = (matvec(G, u_dot) - t * Dd[:, None]) * inv[:, None]
    tdd = (
        matvec(G, u_ddot) + Hdd - 2.0 * (td * Dd[:, None]) - t * (_dot(g, u_ddot) + hdd)[:, None]
    ) * inv[:, None]
    tp = (matvec(G, u_prime) - t * Dp[:, None]) * inv[:, None]
    tdp = (
        matvec(G, u_dot_prime)
        + matvec(Hp, u_dot)
        - td * Dp[:, None]
        - tp * Dd[:, None]
        - t * (_dot(g, u_dot_prime) + _dot(hp, u_dot))[:, None]
    ) * inv[:, None]
    # dt/du and dt'/du, column c: (grad P [e_c] - t grad D [e_c]) / D and
    # (hess P [e_c, u'] - J_c D' - t hess D [e_c, u'] - t' grad D [e_c]) / D
    Jm = (G - t[:, :, None] * g[:, None]) * inv[:, None, None]
    dtm = (
        Hp - Jm * Dp[:, None, None] - t[:, :, None] * hp[:, None] - tp[:, :, None] * g[:, None]
    ) * inv[:, None, None]
    J = [Jm[:, :, c] for c in range(3)]
    dtp = [dtm[:, :, c] for c in range(3)]
    return Fields3D(
        u=u,
        u_dot=u_dot,
        u_ddot=u_ddot,
        u_prime=u_prime,
        u_dot_prime=u_dot_prime,
        t=t,
        t_dot=td,
        t_ddot=tdd,
        t_prime=tp,
        t_dot_prime=tdp,
        J=J,
        dt_prime=dtp,
        fiber=fiber_direction(p),
        fiber_dot=_fiber_rate(p, u_dot),
        t_tip=tangent(u_tip),
    )
