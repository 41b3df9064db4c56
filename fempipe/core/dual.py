"""Forward-mode derivatives of array expressions: exact Jacobians written once with the residual.

A :class:`Dual` is an array value with the derivatives of every entry with
respect to K independent directions (the unknowns of a residual), carried
along by the arithmetic: ``x.der[..., k] = d x.val / d p_k``.  A residual
written with these operations gives its value (``der`` None: no derivative is
formed, no cost) and, from the same lines, its exact Jacobian (``der`` seeded
with the derivatives of the unknown fields): the Jacobian cannot drift from the
residual, and is exact to round-off (no finite differences).

Only what the weak forms need is here: the four operations, sine and cosine,
indexing, sums and stacks along leading axes, vector dot and cross products
over axis 1, and linear maps along axis 0 (the integration operators).
Derivatives come in two parts (``der`` and ``loc``, :class:`Dual`): pointwise
ones stay small until an integral mixes the points.  The
derivative axis is always the last one, so every leading-axis index and
linear map applies to the value and to the derivatives alike.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

__all__ = ["Dual", "cos", "cross", "dot", "sin", "stack"]


def _val(x):
    return x.val if isinstance(x, Dual) else x


def _add(a, b):
    if a is None:
        return b
    if b is None:
        return a
    return a + b


def _parts(x) -> tuple:
    return (x.der, x.loc) if isinstance(x, Dual) else (None, None)


def _bcast(d, shape):
    if d is not None and d.shape[:-1] != shape:
        d = np.broadcast_to(d, shape + d.shape[-1:])
    return d


class Dual:
    """An array with its derivatives along K directions (module docstring).

    Parameters
    ----------
    val : array_like
        The value.
    der : ndarray or None
        Shape ``val.shape + (K,)``: the derivatives with respect to the
        unknowns; None for none.
    loc : ndarray or None
        Shape ``val.shape + (L,)``: derivatives with respect to L quantities
        defined pointwise along axis 0 (the fields and their rates at each
        quadrature point), for values that do not yet depend on other points.
        Every pointwise operation carries both parts alike; a linear map that
        mixes points (:meth:`nonlocal_map`) first expands ``loc`` into
        ``der``.  The two parts add: dx = der + (expansion of loc).
    """

    __slots__ = ("der", "loc", "val")
    __array_ufunc__ = None  # ndarray (op) Dual defers to the reflected operators of Dual

    def __init__(self, val, der: np.ndarray | None = None, loc: np.ndarray | None = None) -> None:
        self.val = np.asarray(val, dtype=float)
        self.der = der
        self.loc = loc

    @property
    def shape(self) -> tuple[int, ...]:
        return self.val.shape

    def _map(self, f) -> tuple:
        return tuple(None if d is None else f(d) for d in (self.der, self.loc))

    def __getitem__(self, idx) -> Dual:
        return Dual(self.val[idx], *self._map(lambda d: d[idx]))

    def __neg__(self) -> Dual:
        return Dual(-self.val, *self._map(np.negative))

    def __add__(self, other) -> Dual:
        val = self.val + _val(other)
        od, ol = _parts(other)
        der = _bcast(_add(self.der, od), val.shape)
        loc = _bcast(_add(self.loc, ol), val.shape)
        return Dual(val, der, loc)

    __radd__ = __add__

    def __sub__(self, other) -> Dual:
        return self + (-other if isinstance(other, Dual) else -np.asarray(other))

    def __rsub__(self, other) -> Dual:
        return (-self) + other

    def __mul__(self, other) -> Dual:
        ov = np.asarray(_val(other))[..., None]
        sv = self.val[..., None]
        out = []
        for mine, theirs in zip((self.der, self.loc), _parts(other), strict=True):
            d = None if mine is None else mine * ov
            if theirs is not None:
                d = _add(d, sv * theirs)
            out.append(d)
        return Dual(self.val * _val(other), *out)

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

    def nonlocal_map(
        self,
        op: Callable[[np.ndarray], np.ndarray],
        expand: Callable[[np.ndarray], np.ndarray] | None = None,
    ) -> Dual:
        """``op`` (linear along axis 0, any trailing axes) of the value and derivatives.

        ``expand`` turns ``loc`` into derivatives with respect to the unknowns
        (``der``'s directions); it is needed when ``loc`` is present.
        """
        der = self.der
        if self.loc is not None:
            if expand is None:
                raise ValueError("a Dual with pointwise derivatives needs expand= to be mapped")
            der = _add(der, expand(self.loc))
        return Dual(op(self.val), None if der is None else op(der))


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


def cross(x, y):
    """The cross product of two vector fields of shape (m, 3, ...) (over axis 1)."""
    x0, x1, x2 = x[:, 0], x[:, 1], x[:, 2]
    y0, y1, y2 = (y[:, 0], y[:, 1], y[:, 2])
    return stack([x1 * y2 - x2 * y1, x2 * y0 - x0 * y2, x0 * y1 - x1 * y0], axis=1)


def stack(items: Sequence, axis: int = 1) -> Dual:
    """Stack Duals (or arrays) of one shape along a leading ``axis`` of the value."""
    if not any(isinstance(x, Dual) for x in items):
        shape = np.broadcast_shapes(*(np.shape(x) for x in items))
        out = np.empty(shape[:axis] + (len(items),) + shape[axis:])
        for k, x in enumerate(items):
            out[(slice(None),) * axis + (k,)] = x
        return out
    vals = [np.asarray(_val(x), dtype=float) for x in items]
    shape = np.broadcast_shapes(*(v.shape for v in vals))
    vals = [np.broadcast_to(v, shape) for v in vals]
    parts = []
    for slot in range(2):
        ds = [_parts(x)[slot] for x in items]
        K = next((d.shape[-1] for d in ds if d is not None), None)
        if K is None:
            parts.append(None)
            continue
        parts.append(
            np.stack(
                [
                    np.zeros(shape + (K,)) if d is None else np.broadcast_to(d, shape + (K,))
                    for d in ds
                ],
                axis=axis,
            )
        )
    return Dual(np.stack(vals, axis=axis), *parts)
