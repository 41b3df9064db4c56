"""Optimal assignment of eigenvalues to predictions or to canonical modes.

Usually every row's cheapest column differs, and that assignment is optimal (one
``argmin``); otherwise the rows left over are added by shortest augmenting paths (Crouse,
IEEE Trans. Aerosp. Electron. Syst. 52 (2016), Algorithm 1, as
:func:`scipy.optimize.linear_sum_assignment`), warm-started from u_i = min_j c_ij, v_j = 0.
Importing :mod:`scipy.optimize` would cost about a third of a command's start-up.
"""

from __future__ import annotations

import numpy as np


def assignment(cost: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of a least-cost assignment, as ``linear_sum_assignment``.

    Parameters
    ----------
    cost : ndarray, shape (m, n), m <= n
        Finite costs.

    Returns
    -------
    rows, cols : ndarray of int
        ``arange(m)`` and each row's column (any one of equal-cost assignments).
    """
    cost = np.asarray(cost, dtype=float)
    m, n = cost.shape
    if m > n:
        raise ValueError(f"cost has more rows ({m}) than columns ({n})")
    if not np.isfinite(cost).all():
        raise ValueError("cost must be finite")
    rows = np.arange(m)
    cols = cost.argmin(axis=1)
    if m == 0 or np.unique(cols).size == m:
        return rows, cols
    u = cost[rows, cols].copy()
    v = np.zeros(n)
    col4row = np.full(m, -1)
    row4col = np.full(n, -1)
    tight = cost == u[:, None]
    for i in range(m):
        free = np.flatnonzero(tight[i] & (row4col < 0))
        if free.size:
            col4row[i], row4col[free[0]] = free[0], i
    for i in np.flatnonzero(col4row < 0):
        _augment(cost, u, v, col4row, row4col, int(i))
    return rows, col4row


def _augment(cost, u, v, col4row, row4col, cur: int) -> None:
    """Assign row ``cur`` along a shortest augmenting path, updating the duals."""
    m, n = cost.shape
    spc = np.full(n, np.inf)  # shortest path costs to each column
    path = np.full(n, -1)
    remaining = np.ones(n, dtype=bool)
    scanned_rows = np.zeros(m, dtype=bool)
    min_val, i, sink = 0.0, cur, -1
    while sink < 0:
        scanned_rows[i] = True
        r = min_val + cost[i] - u[i] - v
        better = remaining & (r < spc)
        spc[better] = r[better]
        path[better] = i
        cand = np.flatnonzero(remaining)
        low = spc[cand].min()
        at_low = cand[spc[cand] == low]
        # Among equal costs prefer an unassigned column: it ends the path.
        unassigned = at_low[row4col[at_low] < 0]
        j = int(unassigned[0] if unassigned.size else at_low[0])
        min_val = float(low)
        remaining[j] = False
        if row4col[j] < 0:
            sink = j
        else:
            i = int(row4col[j])
    u[cur] += min_val
    others = scanned_rows.copy()
    others[cur] = False
    idx = np.flatnonzero(others)
    u[idx] += min_val - spc[col4row[idx]]
    done = ~remaining
    v[done] -= min_val - spc[done]
    j = sink
    while True:
        i = int(path[j])
        row4col[j] = i
        col4row[i], j = j, col4row[i]
        if i == cur:
            break
