"""The pseudo-arclength continuation loop.

One loop for every branch of the package -- static equilibria in v, gamma or
alpha and periodic orbits in v -- written as the algorithm reads in a
textbook (Allgower & Georg, *Introduction to Numerical Continuation Methods*,
Ch. 2; Kuznetsov, Sec. 10.2).  What differs between problems is asked of the
problem (:class:`~fempipe.solvers.continuation.protocol.ContinuationProblem`)
and of its policy (:class:`~fempipe.solvers.continuation.protocol.ContinuationPolicy`).
"""

from __future__ import annotations

from typing import Any

from .protocol import ContinuationPolicy, CorrectorError

__all__ = ["continue_curve"]


def continue_curve(policy: ContinuationPolicy, h: float) -> Any:
    """Follow a curve F(y) = 0 from its last known point with first step ``h``.

    Every step is

    1. **predict** -- a point at arclength ``h`` ahead (on the tangent, on a
       secant or on a polynomial through the last points);
    2. **correct** -- Newton's method back onto the curve, with the
       pseudo-arclength condition <t, y - y_pred> = 0 as the extra equation
       (or a fixed parameter, where a requested value lies ahead);
    3. **accept** -- the corrected point is refused when the curve turned too
       sharply (a jump to another branch); a refused or failed step is
       **rejected**: retried with a shorter step, down to a minimum;
    4. **land** -- a requested parameter value passed by the step is landed on
       exactly;
    5. **detect** -- special points between the last two points are found by
       the sign changes of test functions (the parameter component of the
       tangent at folds, the determinant of the bordered matrix at branch
       points) and located (bisection, or the secant of the test function);
    6. **step control** -- the next step grows when the corrector converged
       quickly and shrinks when it did not.

    Parameters
    ----------
    policy : ContinuationPolicy
        The problem's choices for each of these steps, holding the branch.
    h : float
        The first step length (arclength in the problem's inner product).

    Returns
    -------
    object
        What ``policy.finish`` returns: the branch.
    """
    while True:
        reason = policy.stop_before()
        if reason is not None:
            return policy.finish(reason, h)
        step = policy.predict(h)
        failure = None
        try:
            point = policy.correct(step)
            policy.accept(step, point)
        except CorrectorError as exc:
            failure = exc
        if failure is not None:
            # (Outside the handler: the error of a stalled branch is not
            # chained to the failure of its last step.)
            h = policy.reject(step, h, failure)
            continue
        point = policy.land(step, point)
        policy.detect(step, point)
        policy.append(point)
        h = policy.next_step(step, point, h)
        policy.notify(point, h)
        reason = policy.stop_after(step, point)
        if reason is not None:
            return policy.finish(reason, h)
