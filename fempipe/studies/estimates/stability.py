"""Error estimates of a stability analysis: the analysis run again on the refined discretization.

The events of the two runs are paired by what they are (branch, type, mode,
plane), and beside v_cr, v_flutter and the ``v`` and ``frequency`` of every
event ``Q_error`` and ``Q_refined`` are inserted; the floor is
:data:`EVENT_TOL`, to which the events are located (``fempipe critical
--error-estimate``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from fempipe.core.errors import SolverError
from fempipe.studies.error_estimate import describe, match_events, refine

from .shape import ERROR, REFINED, Refined, beside, header, with_estimate

__all__ = ["EVENT_TOL", "RefinedStability", "refined_stability", "with_stability_estimates"]

#: Events are located to 1e-10 in v (Brent; folds by the continuation): the
#: floor of the estimates of the stability events, relative to max(1, |Q|).
EVENT_TOL = 1e-10


@dataclass(frozen=True)
class RefinedStability(Refined):
    """:func:`refined_stability`: ``result`` is the refined ``StabilityResult`` (or the
    spatial one), None if the refined run failed."""

    result: object = None


def refined_stability(
    model,
    *,
    planar: bool = False,
    fine=None,
    callback: Callable[[str, float], None] | None = None,
    **options,
) -> RefinedStability:
    """The stability analysis run again on the refined discretization.

    Parameters
    ----------
    model : PipeModel
        The reported model.
    planar : bool
        :func:`fempipe.analyses.stability.stability_analysis` (the planar model)
        if True, else :func:`~fempipe.analyses.stability.spatial_stability_analysis`:
        the analysis of the reported result.
    fine : FiniteElement or Modal, optional
        ``refine(model.disc)`` if already built.
    callback : callable, optional
        ``callback(branch, v)`` at each sample of the refined run.
    **options
        The keyword arguments of the reported analysis (``v_max``, ``ds_max``, ...).

    Returns
    -------
    RefinedStability
        ``result`` None, with a note, if the refined run failed; a note if
        its primary branch ran out of continuation steps.
    """
    # Imported here: the CLI loads this module at start-up (--help); these load scipy.
    from fempipe.analyses.stability import spatial_stability_analysis, stability_analysis
    from fempipe.model.operators import PipeModel

    analysis = stability_analysis if planar else spatial_stability_analysis
    fine = refine(model.disc) if fine is None else fine
    info = describe(
        model.disc,
        fine,
        floor=f"events located to {EVENT_TOL:g} max(1, |Q|)",
        params=model.params,
    )
    try:
        res = analysis(PipeModel(fine, model.params), callback=callback, **options)
    except (SolverError, ValueError) as exc:
        notes = (f"the refined run on {fine.name} failed ({exc}); no estimates",)
        return RefinedStability(fine, info, notes, None)
    notes = []
    branches = res.branches if hasattr(res, "branches") else res.in_plane.branches
    primary = next((b for b in branches if b.name == "primary"), None)
    if primary is not None and primary.end_reason == "max_steps":
        notes.append(
            f"the refined run's primary branch ran out of continuation steps at "
            f"v = {float(primary.v.max()):.6g}"
        )
    return RefinedStability(fine, info, tuple(notes), res)


def with_stability_estimates(result: dict, res, refined: RefinedStability, pipe=None) -> dict:
    """``result`` with ``Q_error``, ``Q_refined`` beside the numbers of a stability analysis.

    The events of the two runs are paired by branch, type, mode and plane
    (:func:`~fempipe.studies.error_estimate.match_events`, not by position).
    Beside ``v`` and ``frequency`` of every event and of ``critical`` (and
    ``critical_in_plane``, ``critical_out_of_plane``), beside ``v_cr``,
    ``v_flutter``, ``v_cr_in_plane``, ``v_cr_out_of_plane`` and ``U_cr``
    the estimate and the refined value are inserted.  Every event gets
    ``error_note``: None, or why it has no estimate; ``v_cr_error`` is None,
    with a note, when the refined run loses stability first by another event.

    Parameters
    ----------
    result : dict
        ``res.to_dict()``, decorated (``U_cr`` with an SI pipe).
    res : StabilityResult or SpatialStabilityResult
        The reported analysis.
    refined : RefinedStability
        :func:`refined_stability` of the same analysis.
    pipe : PipeSI, optional

    Returns
    -------
    dict
        With the top-level ``"error_estimate"`` (:func:`header`), whose notes
        also list refined events the reported run lacks.
    """
    return _StabilityEstimates(res, refined).attach(result, pipe)


class _StabilityEstimates:
    """The pairing of a stability analysis's events with the refined run's."""

    def __init__(self, res, refined: RefinedStability) -> None:
        self.res, self.fine_res = res, refined.result
        self.info = refined.info
        self.notes = list(refined.notes)
        self.order, self.name = refined.info.order, refined.info.refined
        self.fine_events = [] if self.fine_res is None else list(self.fine_res.events)
        self.pairs, self.unmatched = match_events(res.events, self.fine_events)

    def partner(self, ev):
        """The refined event paired with the coarse event ``ev`` (a StabilityEvent)."""
        i = next((i for i, e in enumerate(self.res.events) if e == ev), None)
        return None if i is None or self.pairs[i] is None else self.fine_events[self.pairs[i]]

    def add(self, d: dict, f) -> dict:
        """``d`` with the estimates of its ``v`` and ``frequency`` against the event ``f``."""
        info = self.info
        d = with_estimate(
            d, "v", None if f is None else f.v, self.order, EVENT_TOL, ratio=info.ratio
        )
        return with_estimate(
            d,
            "frequency",
            None if f is None else f.frequency,
            self.order,
            EVENT_TOL,
            ratio=info.ratio,
        )

    def events(self, result: dict) -> None:
        """Every event of ``result`` with its estimates and ``error_note``."""
        res, name = self.res, self.name
        events = []
        for ev, d in zip(res.events, result["events"], strict=True):
            f = self.partner(ev)
            d = self.add(d, f)
            d["error_note"] = None
            if f is None and self.fine_res is not None:
                d["error_note"] = (
                    f"no {ev.type} of mode {ev.mode} on branch {ev.branch} in the refined run ({name})"
                )
            events.append(d)
        result["events"] = events
        for j in self.unmatched:
            f = self.fine_events[j]
            self.notes.append(
                f"the refined run ({name}) has a {f.type} of mode {f.mode} on branch {f.branch} "
                f"at v = {f.v:.10g} that the reported run has not"
            )

    def first(self, result: dict, key: str, coarse_ev, fine_value) -> dict:
        """``key`` (v_cr or v_flutter) with its estimate: only if both runs' event is one."""
        name = self.name
        f = None if coarse_ev is None else self.partner(coarse_ev)
        same = f is not None and fine_value is not None and f.v == fine_value
        if result[key] is not None and self.fine_res is not None and not same:
            what = "none" if fine_value is None else f"v = {fine_value:.10g}"
            self.notes.append(
                f"{key}: the refined run ({name}) gives {what} by another event than the "
                f"reported one; no estimate"
            )
        elif result[key] is None and fine_value is not None:
            self.notes.append(f"{key}: none in the reported run, v = {fine_value:.10g} refined")
        refined = fine_value if same else None
        out = with_estimate(result, key, refined, self.order, EVENT_TOL, ratio=self.info.ratio)
        out[key + REFINED] = fine_value
        return out

    def attach(self, result: dict, pipe) -> dict:
        """``result`` with every estimate and the ``"error_estimate"`` header."""
        res, fine_res = self.res, self.fine_res
        self.events(result)
        v_flutter_ev = min(
            (e for e in res.events if e.branch == "primary" and e.type == "flutter"),
            key=lambda e: e.v,
            default=None,
        )
        result = self.first(
            result, "v_cr", res.critical, None if fine_res is None else fine_res.v_cr
        )
        result = self.first(
            result, "v_flutter", v_flutter_ev, None if fine_res is None else fine_res.v_flutter
        )
        if hasattr(res, "in_plane"):
            for plane in ("in_plane", "out_of_plane"):
                coarse, fine = (
                    getattr(res, plane),
                    None if fine_res is None else getattr(fine_res, plane),
                )
                result = self.first(
                    result, "v_cr_" + plane, coarse.critical, None if fine is None else fine.v_cr
                )
        if result["critical"] is not None:
            result["critical"] = self.add(result["critical"], self.partner(res.critical))
        for plane in ("in_plane", "out_of_plane") if hasattr(res, "in_plane") else ():
            key = "critical_" + plane
            if result.get(key) is not None:
                result[key] = self.add(result[key], self.partner(getattr(res, plane).critical))
        if pipe is not None and "U_cr" in result:
            err, fine_v = result["v_cr" + ERROR], result["v_cr" + REFINED]
            scale = pipe.U_of_v(1.0)
            result = beside(
                result,
                "U_cr",
                {
                    "U_cr" + ERROR: None if err is None else err * scale,
                    "U_cr" + REFINED: None if fine_v is None else pipe.U_of_v(fine_v),
                },
            )
        result["error_estimate"] = header(self.info, self.notes)
        return result
