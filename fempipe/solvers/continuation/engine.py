"""The pseudo-arclength continuation loop, one for every branch of the package.

Static equilibria in v, gamma or alpha and periodic orbits in v, written as in Allgower &
Georg (Ch. 2) and Kuznetsov (Sec. 10.2); what differs is asked of the problem and of its
policy (:mod:`~fempipe.solvers.continuation.protocol`).  Derivation: docs/theory/numerics.md.
"""

from __future__ import annotations

from typing import Any

from .protocol import ContinuationPolicy, CorrectorError

__all__ = ["continue_curve"]


def continue_curve(policy: ContinuationPolicy, h: float) -> Any:
    """Follow a curve F(y) = 0 from its last known point with first step ``h``, each choice the
    ``policy``'s (docs/theory/numerics.md); return the branch."""
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
