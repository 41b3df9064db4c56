"""Brent's bracketing root finder, without importing :mod:`scipy.optimize`.

Importing :mod:`scipy.optimize` for one scalar root finder would cost about a third of a
command's start-up.  :func:`brentq` is Brent's algorithm (*Algorithms for Minimization
without Derivatives*, 1973, Ch. 4) step for step as scipy's C code writes it, so its roots
are the same floating-point numbers as ``scipy.optimize.brentq``'s (tested).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

#: The smallest relative tolerance scipy's brentq accepts.
RTOL_MIN = 4 * float(np.finfo(float).eps)


def brentq(
    f: Callable[[float], float],
    a: float,
    b: float,
    xtol: float = 2e-12,
    rtol: float = RTOL_MIN,
    maxiter: int = 100,
) -> float:
    """A root of ``f`` in the bracket ``[a, b]`` by Brent's method, as ``scipy.optimize.brentq``.

    Parameters
    ----------
    f : callable
        Scalar function; ``f(a)`` and ``f(b)`` differ in sign.
    a, b : float
        The bracket.
    xtol, rtol : float
        Returned once known to within ``xtol + rtol * |x|`` (``xtol > 0``, ``rtol >= 4 eps``).
    maxiter : int
        Most iterations before :class:`RuntimeError`.

    Raises
    ------
    ValueError
        Bad tolerances, no sign change, or ``f`` not finite.
    """
    if not xtol > 0:
        raise ValueError(f"xtol must be > 0, got {xtol}")
    if not rtol >= RTOL_MIN:
        raise ValueError(f"rtol must be >= {RTOL_MIN:g}, got {rtol}")
    if maxiter < 0:
        raise ValueError(f"maxiter must be >= 0, got {maxiter}")

    def value(x: float) -> float:
        fx = float(f(x))
        if not math.isfinite(fx):
            raise ValueError(f"the function value at x={x!r} is {fx!r}")
        return fx

    xpre, xcur = float(a), float(b)
    fpre, fcur = value(xpre), value(xcur)
    if fpre == 0.0:
        return xpre
    if fcur == 0.0:
        return xcur
    if math.copysign(1.0, fpre) == math.copysign(1.0, fcur):
        raise ValueError("f(a) and f(b) must have different signs")
    xblk = fblk = spre = scur = 0.0
    for _ in range(maxiter):
        if fpre != 0.0 and fcur != 0.0 and math.copysign(1.0, fpre) != math.copysign(1.0, fcur):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0.0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:
                stry = -fcur * (xcur - xpre) / (fcur - fpre)  # secant
            else:
                # inverse quadratic interpolation
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):
                spre, scur = scur, stry
            else:
                spre = scur = sbis
        else:
            spre = scur = sbis
        xpre, fpre = xcur, fcur
        xcur += scur if abs(scur) > delta else (delta if sbis > 0 else -delta)
        fcur = value(xcur)
    raise RuntimeError(f"brentq: no convergence in {maxiter} iterations (last x={xcur!r})")
