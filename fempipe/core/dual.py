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
over axis 1, and linear maps along axis 0 (the integration operators).  The
derivative axis is always the last one, so every leading-axis index and
linear map applies to the value and to the derivatives alike.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

__all__ = ["Dual", "cross", "dot", "stack"]


def _val(x):
    return x.val if isinstance(x, Dual) else x


def _der(x):
    return x.der if isinstance(x, Dual) else None


def _add(a, b):
    if a is None:
        return b
    if b is None:
        return a
    return a + b


class Dual:
    """An array with its derivatives along K directions (module docstring).

    Parameters
    ----------
    val : array_like
        The value.
    der : ndarray or None
        Shape ``val.shape + (K,)``; None for a constant.
    """

    __slots__ = ("der", "val")
    __array_ufunc__ = None  # ndarray (op) Dual defers to the reflected operators of Dual

    def __init__(self, val, der: np.ndarray | None = None) -> None:
        self.val = np.asarray(val, dtype=float)
        self.der = der

    @property
    def shape(self) -> tuple[int, ...]:
        return self.val.shape

    def __getitem__(self, idx) -> Dual:
        return Dual(self.val[idx], None if self.der is None else self.der[idx])

    def __neg__(self) -> Dual:
        return Dual(-self.val, None if self.der is None else -self.der)

    def __add__(self, other) -> Dual:
        val = self.val + _val(other)
        d = _add(self.der, _der(other))
        if d is not None and d.shape[:-1] != val.shape:
            d = np.broadcast_to(d, val.shape + d.shape[-1:])
        return Dual(val, d)

    __radd__ = __add__

    def __sub__(self, other) -> Dual:
        return self + (-other if isinstance(other, Dual) else -np.asarray(other))

    def __rsub__(self, other) -> Dual:
        return (-self) + other

    def __mul__(self, other) -> Dual:
        ov = _val(other)
        d = None
        if self.der is not None:
            d = self.der * np.asarray(ov)[..., None]
        od = _der(other)
        if od is not None:
            d = _add(d, self.val[..., None] * od)
        return Dual(self.val * ov, d)

    __rmul__ = __mul__

    def __truediv__(self, other) -> Dual:
        if isinstance(other, Dual):
            return self * other.reciprocal()
        return self * (1.0 / np.asarray(other, dtype=float))

    def __rtruediv__(self, other) -> Dual:
        return self.reciprocal() * other

    def reciprocal(self) -> Dual:
        r = 1.0 / self.val
        return Dual(r, None if self.der is None else -(r * r)[..., None] * self.der)

    def sin(self) -> Dual:
        d = None if self.der is None else np.cos(self.val)[..., None] * self.der
        return Dual(np.sin(self.val), d)

    def cos(self) -> Dual:
        d = None if self.der is None else -np.sin(self.val)[..., None] * self.der
        return Dual(np.cos(self.val), d)

    def sum(self, axis: int) -> Dual:
        """The sum over a leading axis (``axis`` >= 0, counted in the value)."""
        return Dual(self.val.sum(axis=axis), None if self.der is None else self.der.sum(axis=axis))

    def linear(self, op: Callable[[np.ndarray], np.ndarray]) -> Dual:
        """``op`` (linear, acting along axis 0 whatever the trailing axes) of value and derivatives."""
        return Dual(op(self.val), None if self.der is None else op(self.der))


def dot(x: Dual, y) -> Dual:
    """The dot product over axis 1 of two vector fields of shape (m, 3)."""
    return (x * y).sum(axis=1) if isinstance(x, Dual) else (y * x).sum(axis=1)


def cross(x: Dual, y) -> Dual:
    """The cross product of two vector fields of shape (m, 3) (over axis 1)."""
    x0, x1, x2 = x[:, 0], x[:, 1], x[:, 2]
    y0, y1, y2 = (y[:, 0], y[:, 1], y[:, 2])
    return stack([x1 * y2 - x2 * y1, x2 * y0 - x0 * y2, x0 * y1 - x1 * y0], axis=1)


def stack(items: Sequence, axis: int = 1) -> Dual:
    """Stack Duals (or arrays) of one shape along a leading ``axis`` of the value."""
    vals = [np.asarray(_val(x), dtype=float) for x in items]
    shape = np.broadcast_shapes(*(v.shape for v in vals))
    vals = [np.broadcast_to(v, shape) for v in vals]
    ders = [_der(x) for x in items]
    K = next((d.shape[-1] for d in ders if d is not None), None)
    der = None
    if K is not None:
        der = np.stack(
            [
                np.zeros(shape + (K,)) if d is None else np.broadcast_to(d, shape + (K,))
                for d in ders
            ],
            axis=axis,
        )
    return Dual(np.stack(vals, axis=axis), der)
