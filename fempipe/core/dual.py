"""Derivatives of array expressions: forward through pointwise arithmetic, reverse through integrals.

A :class:`Dual` is an array value with its derivatives, carried along by the arithmetic: a
residual written with these operations gives its value and, from the same lines, its exact
Jacobian.  Derivatives are kept with respect to quantities at the same point and to the
:class:`Term` objects that mix the points; :func:`pullback` contracts them at the end, in
reverse.  Only what the weak forms need is here (the four operations, sin, cos, indexing,
sums and stacks, dot and cross over axis 1, linear maps along axis 0).

Derivation: docs/theory/space.md, "The weak form" (the 3-D model is written on it).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence

import numpy as np

__all__ = [
    "Dual",
    "Term",
    "cos",
    "cross",
    "dot",
    "linear_functional",
    "matvec",
    "pullback",
    "sin",
    "stack",
]

_ORDER = itertools.count()


def _val(x):
    return x.val if isinstance(x, Dual) else x


def _bcast(d, shape):
    if d is not None and d.shape[:-1] != shape:
        d = np.broadcast_to(d, shape + d.shape[-1:])
    return d


def _add(a, b):
    if a is None:
        return b
    if b is None:
        return a
    return a + b


def _merge(a: dict | None, b: dict | None, shape) -> dict | None:
    if not b:
        return None if not a else {t: _bcast(c, shape) for t, c in a.items()}
    if not a:
        return {t: _bcast(c, shape) for t, c in b.items()}
    out = dict(a)
    for t, c in b.items():
        out[t] = out[t] + c if t in out else c
    return {t: _bcast(c, shape) for t, c in out.items()}


class Term:
    """A quantity Y that mixes the points: its value, and how its derivative is pulled back.

    ``n`` points (1: broadcast), ``m`` components per point and state.  Either ``Y = A X``
    along axis 0 for a :class:`Dual` X (``adjoint`` applies A^T along axis 0), or Y linear in
    the unknowns with the dense derivative ``gder`` (shape (n_points, m, K)).  Terms are
    ordered by creation, inner before outer (:func:`pullback` relies on it).
    """

    __slots__ = ("adjoint", "gder", "identity", "loc", "m", "n", "nl", "order")

    def __init__(self, n: int, m: int, adjoint=None, loc=None, nl=None, gder=None) -> None:
        self.n = n
        self.m = m
        self.adjoint = adjoint
        self.loc = loc
        self.nl = nl
        self.gder = gder
        self.order = next(_ORDER)
        self.identity = None

    def identity_for(self, val: np.ndarray) -> np.ndarray:
        """dY/dY for the value ``val`` of Y: the identity on the components, broadcast over
        points and states (kept, so that a map of Y itself can be recognized)."""
        n, *comp, S = val.shape
        eye = np.eye(self.m).reshape(tuple(comp) + (1, self.m))
        self.identity = np.broadcast_to(eye[None], val.shape + (self.m,))
        return self.identity


class Dual:
    """An array with its derivatives (docs/theory/space.md, "The weak form").

    Parameters
    ----------
    val : array_like
        The value; axis 0 the points, the last axis the S states.
    loc : ndarray or None
        Shape ``val.shape + (L,)``: derivatives with respect to L quantities defined at each
        point (each state's at its own).
    nl : dict or None
        :class:`Term` -> ndarray of shape ``val.shape + (term.m,)``: derivatives with respect to
        each term's components at the same point and state.
    """

    __slots__ = ("loc", "nl", "val")
    __array_ufunc__ = None  # ndarray (op) Dual defers to the reflected operators of Dual

    def __init__(self, val, loc: np.ndarray | None = None, nl: dict | None = None) -> None:
        self.val = np.asarray(val, dtype=float)
        self.loc = loc
        self.nl = nl or None

    @property
    def shape(self) -> tuple[int, ...]:
        return self.val.shape

    def _map(self, f) -> tuple:
        loc = None if self.loc is None else f(self.loc)
        nl = None if self.nl is None else {t: f(c) for t, c in self.nl.items()}
        return loc, nl

    def __getitem__(self, idx) -> Dual:
        return Dual(self.val[idx], *self._map(lambda d: d[idx]))

    def __neg__(self) -> Dual:
        return Dual(-self.val, *self._map(np.negative))

    def __add__(self, other) -> Dual:
        val = self.val + _val(other)
        if isinstance(other, Dual):
            loc = _bcast(_add(self.loc, other.loc), val.shape)
            return Dual(val, loc, _merge(self.nl, other.nl, val.shape))
        return Dual(val, _bcast(self.loc, val.shape), _merge(self.nl, None, val.shape))

    __radd__ = __add__

    def __sub__(self, other) -> Dual:
        return self + (-other if isinstance(other, Dual) else -np.asarray(other))

    def __rsub__(self, other) -> Dual:
        return (-self) + other

    def __mul__(self, other) -> Dual:
        # Every part has the shape of its value plus one axis, so the products below
        # broadcast to the product's shape by themselves.
        if not isinstance(other, Dual):
            if isinstance(other, float | int):
                return Dual(self.val * other, *self._map(lambda d: d * other))
            ov = np.asarray(other)
            ox = ov[..., None]
            return Dual(self.val * ov, *self._map(lambda d: d * ox))
        ov, sv = other.val, self.val
        ox, sx = ov[..., None], sv[..., None]
        loc = None if self.loc is None else self.loc * ox
        if other.loc is not None:
            loc = other.loc * sx if loc is None else loc + other.loc * sx
        nl = None if self.nl is None else {t: c * ox for t, c in self.nl.items()}
        if other.nl is not None:
            nl = {} if nl is None else nl
            for t, c in other.nl.items():
                nl[t] = nl[t] + c * sx if t in nl else c * sx
        return Dual(sv * ov, loc, nl)

    __rmul__ = __mul__

    def __truediv__(self, other) -> Dual:
        if isinstance(other, Dual):
            return self * other.reciprocal()
        return self * (1.0 / np.asarray(other, dtype=float))

    def __rtruediv__(self, other) -> Dual:
        return self.reciprocal() * other

    def reciprocal(self) -> Dual:
        r = 1.0 / self.val
        m = -(r * r)[..., None]
        return Dual(r, *self._map(lambda d: m * d))

    def sin(self) -> Dual:
        c = np.cos(self.val)[..., None]
        return Dual(np.sin(self.val), *self._map(lambda d: c * d))

    def cos(self) -> Dual:
        s = -np.sin(self.val)[..., None]
        return Dual(np.cos(self.val), *self._map(lambda d: s * d))

    def sum(self, axis: int) -> Dual:
        """The sum over a leading axis (``axis`` >= 0, counted in the value)."""
        return Dual(self.val.sum(axis=axis), *self._map(lambda d: d.sum(axis=axis)))

    def nonlocal_map(self, op: Callable[[np.ndarray], np.ndarray], adjoint) -> Dual:
        """``op`` (linear along axis 0) of the value, its derivative carried as a new :class:`Term`;
        ``adjoint``: op^T, a matrix (n_in, n_out) (two nested ones make one term) or a callable."""
        val = op(self.val)
        if self.loc is None and self.nl is None:
            return Dual(val)
        loc, nl = self.loc, self.nl
        if loc is None and len(nl) == 1:
            ((inner, coef),) = nl.items()
            if (
                coef is inner.identity
                and isinstance(adjoint, np.ndarray)
                and isinstance(inner.adjoint, np.ndarray)
            ):
                adjoint = inner.adjoint @ adjoint
                loc, nl = inner.loc, inner.nl
        m = int(np.prod(self.val.shape[1:-1], dtype=int))
        term = Term(val.shape[0], m, adjoint=adjoint, loc=loc, nl=nl)
        return Dual(val, None, {term: term.identity_for(val)})


def linear_functional(val: np.ndarray, gder: np.ndarray) -> Dual:
    """A Dual Y linear in the unknowns: ``gder`` (shape (n_points, m, K)) is dY/d(unknowns),
    the same for every state."""
    val = np.asarray(val, dtype=float)
    term = Term(val.shape[0], gder.shape[1], gder=gder)
    return Dual(val, None, {term: term.identity_for(val)})


def _flat(d: np.ndarray, n: int, S: int) -> np.ndarray:
    """(n, *comp, S, k) -> (n, S, k, m) with m = prod(comp)."""
    d = d.reshape(n, -1, S, d.shape[-1])
    return d.transpose(0, 2, 3, 1)


def pullback(pairs: Sequence[tuple[Dual, np.ndarray]], L: int):
    """The derivatives of ``sum_x seed_x . dx`` by reverse accumulation through the terms.

    Parameters
    ----------
    pairs : sequence of (Dual, seed)
        ``seed`` of shape (n_x, S, m_x, R): output r gets ``sum_(q, m) seed[q, s, m, r] dx[q, m, s]``.
    L : int
        The number of local quantities (``loc``'s last axis).

    Returns
    -------
    (W, G)
        W, shape (n_points, S, L, R): derivatives with respect to the local quantities (to be
        multiplied by their bases); G, shape (S, R, K): the part through linear functionals,
        or None.
    """
    G = None
    seeds: dict[Term, np.ndarray] = {}
    local: list[tuple[np.ndarray, np.ndarray]] = []  # (seed, loc) pairs, one product at the end

    def visit(loc, nl, seed):
        n, S, m, R = seed.shape
        if loc is not None:
            local.append((seed, _flat(loc, n, S)))
        if not nl:
            return
        # one batched product for all the terms (the products are small)
        coefs = np.concatenate([_flat(c, n, S) for c in nl.values()], axis=2)
        both = np.matmul(coefs, seed)  # (n, S, sum of the terms' m, R)
        at = 0
        for term in nl:
            part = both[:, :, at : at + term.m]
            at += term.m
            if term.n != n:  # Y at its one point, broadcast to the n points of x
                part = part.sum(axis=0, keepdims=True)
            seeds[term] = seeds[term] + part if term in seeds else part

    for x, seed in pairs:
        visit(x.loc, x.nl, np.ascontiguousarray(seed))
    while seeds:
        term = max(seeds, key=lambda t: t.order)
        seed = seeds.pop(term)
        n_out, S, m, R = seed.shape
        if term.gder is not None:
            g = np.einsum("qsmr,qmk->srk", seed, term.gder)
            G = g if G is None else G + g
            continue
        flat = np.ascontiguousarray(seed).reshape(n_out, -1)
        adj = term.adjoint
        inner = adj @ flat if isinstance(adj, np.ndarray) else adj(flat)
        visit(term.loc, term.nl, inner.reshape(-1, S, m, R))
    W = None
    if local:
        W = np.matmul(
            np.concatenate([loc for _, loc in local], axis=3),
            np.concatenate([seed for seed, _ in local], axis=2),
        )
    return W, G


def sin(x):
    """sin of a Dual or an array."""
    return x.sin() if isinstance(x, Dual) else np.sin(x)


def cos(x):
    """cos of a Dual or an array."""
    return x.cos() if isinstance(x, Dual) else np.cos(x)


def dot(x, y):
    """The dot product over axis 1 of two vector fields of shape (m, 3, ...) (Duals or arrays)."""
    return (
        (x * y).sum(axis=1)
        if isinstance(x, Dual) or not isinstance(y, Dual)
        else (y * x).sum(axis=1)
    )


def matvec(M, v):
    """``M v`` at every point and state, M (m, 3, 3, S), v (m, 3, S): ``(M * v[:, None]).sum(2)``
    without its (m, 3, 3, S, L) product."""
    if not isinstance(M, Dual) and not isinstance(v, Dual):
        return np.einsum("nijs,njs->nis", M, v)
    Mv, vv = _val(M), _val(v)
    val = np.einsum("nijs,njs->nis", Mv, vv)
    loc, nl = None, {}
    if isinstance(M, Dual):
        if M.loc is not None:
            loc = np.einsum("nijsl,njs->nisl", M.loc, vv)
        for t, c in (M.nl or {}).items():
            nl[t] = np.einsum("nijsl,njs->nisl", c, vv)
    if isinstance(v, Dual):
        if v.loc is not None:
            part = np.einsum("nijs,njsl->nisl", Mv, v.loc)
            loc = part if loc is None else loc + part
        for t, c in (v.nl or {}).items():
            part = np.einsum("nijs,njsl->nisl", Mv, c)
            nl[t] = nl[t] + part if t in nl else part
    return Dual(val, loc, nl)


def cross(x, y):
    """The cross product of two vector fields of shape (m, 3, ...) (over axis 1)."""
    x0, x1, x2 = x[:, 0], x[:, 1], x[:, 2]
    y0, y1, y2 = (y[:, 0], y[:, 1], y[:, 2])
    return stack([x1 * y2 - x2 * y1, x2 * y0 - x0 * y2, x0 * y1 - x1 * y0], axis=1)


def stack(items: Sequence, axis: int = 1) -> Dual:
    """Stack Duals (or arrays) of one shape along a leading ``axis`` of the value."""
    if not any(isinstance(x, Dual) for x in items):
        shapes = [np.shape(x) for x in items]
        # (the residual's path: items of one shape are the rule, and broadcast_shapes
        # costs more than the copy)
        shape = (
            shapes[0] if shapes.count(shapes[0]) == len(shapes) else np.broadcast_shapes(*shapes)
        )
        out = np.empty(shape[:axis] + (len(items),) + shape[axis:])
        for k, x in enumerate(items):
            out[(slice(None),) * axis + (k,)] = x
        return out
    vals = [np.asarray(_val(x), dtype=float) for x in items]
    shape = np.broadcast_shapes(*(v.shape for v in vals))
    val = np.empty(shape[:axis] + (len(items),) + shape[axis:])
    at = (slice(None),) * axis
    for k, v in enumerate(vals):
        val[at + (k,)] = v

    def stacked(parts: list, width: int) -> np.ndarray:
        out = np.zeros(val.shape + (width,))
        for k, d in enumerate(parts):
            if d is not None:
                out[at + (k,)] = d
        return out

    duals = [x for x in items if isinstance(x, Dual)]
    locs = [x.loc if isinstance(x, Dual) else None for x in items]
    L = next((d.shape[-1] for d in locs if d is not None), None)
    loc = None if L is None else stacked(locs, L)
    terms: dict[Term, None] = {}
    for x in duals:
        for t in x.nl or ():
            terms[t] = None
    nl = {
        t: stacked([x.nl.get(t) if isinstance(x, Dual) and x.nl else None for x in items], t.m)
        for t in terms
    }
    return Dual(val, loc, nl)
