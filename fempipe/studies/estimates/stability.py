"""Error estimates of a stability analysis: the analysis run again on the refined discretization.

The events of the two runs are paired by what they are (branch, type, mode, plane); the floor
is :data:`EVENT_TOL`, to which events are located.  docs/cli/options.md, "Error estimates".
"""

from __future__ import annotations

from collections.abc import Callable

# the module, not its names: a test replaces its analyse_stability
from fempipe.analyses import stability
from fempipe.core.errors import SolverError
from fempipe.model.plane.operators import PipeModel
from fempipe.studies.error_estimate import ERROR, REFINED, describe, match_events, refine

from .shape import beside, header, pair, with_estimate

__all__ = ["EVENT_TOL", "estimate_stability_errors"]

#: Events are located to 1e-10 in v: the floor of their estimates, relative to max(1, |Q|).
EVENT_TOL = 1e-10

#: The keys of each plane's numbers in the JSON of an analysis in both planes.
_PLANE_KEYS = ("in_plane", "out_of_plane")


def estimate_stability_errors(
    result: dict,
    model: PipeModel,
    res,
    *,
    pipe=None,
    fine=None,
    callback: Callable[[str, float], None] | None = None,
    **options,
) -> dict:
    """``result`` with ``Q_error``, ``Q_refined`` beside the numbers of a stability analysis.

    Beside ``v`` and ``frequency`` of every event and of ``critical`` (and of each plane's),
    beside ``v_cr``, ``v_flutter``, each plane's ``v_cr`` and ``U_cr``.  Every event gets
    ``error_note`` (None, or why it has no estimate); ``v_cr_error`` is None, with a note,
    when the refined run loses stability first by another event.

    Parameters
    ----------
    result : dict
        ``res.to_dict()``, decorated (``U_cr`` with an SI pipe).
    model : PipeModel
    res : StabilityResult or StabilityInPlanes
        The reported analysis, run again in its planes (a StabilityResult: in the plane).
    pipe, fine, callback : PipeSI, FiniteElement or Modal, callable, optional
        The SI pipe; ``refine(model.disc)`` if built; ``callback(branch, v)`` per sample.
    **options
        The keyword arguments of the reported analysis (``v_max``, ``ds_max``, ...).
    """
    fine = refine(model.disc) if fine is None else fine
    info = describe(
        model.disc, fine, floor=f"events located to {EVENT_TOL:g} max(1, |Q|)", params=model.params
    )
    options = {"planes": stability.PLANES if hasattr(res, "in_plane") else ("in",), **options}
    try:
        fine_res = stability.analyse_stability(
            PipeModel(fine, model.params), callback=callback, **options
        )
    except (SolverError, ValueError) as exc:
        fine_res, notes = None, [f"the refined run on {fine.name} failed ({exc}); no estimates"]
    else:
        notes = []
        branches = (
            fine_res.branches if hasattr(fine_res, "branches") else fine_res.in_plane.branches
        )
        primary = next((b for b in branches if b.name == "primary"), None)
        if primary is not None and primary.end_reason == "max_steps":
            notes.append(
                f"the refined run's primary branch ran out of continuation steps at "
                f"v = {float(primary.v.max()):.6g}"
            )
    return _Pairing(res, fine_res, info, notes).attach(result, pipe)


class _Pairing:
    """The events of a stability analysis paired with those of the refined run."""

    def __init__(self, res, fine_res, info, notes: list[str]) -> None:
        self.res, self.fine_res, self.info, self.notes = res, fine_res, info, notes
        self.fine_events = [] if fine_res is None else list(fine_res.events)
        self.pairs, self.unmatched = match_events(res.events, self.fine_events)

    def partner(self, ev):
        """The refined event paired with the coarse event ``ev``."""
        i = next((i for i, e in enumerate(self.res.events) if e == ev), None)
        return None if i is None or self.pairs[i] is None else self.fine_events[self.pairs[i]]

    def add(self, d: dict, f) -> dict:
        """``d`` with the estimates of its ``v`` and ``frequency`` against the event ``f``."""
        for key in ("v", "frequency"):
            fine = None if f is None else getattr(f, key)
            d = with_estimate(d, key, fine, self.info.order, EVENT_TOL, ratio=self.info.ratio)
        return d

    def events(self, result: dict) -> None:
        """Every event of ``result`` with its estimates and ``error_note``."""
        name, events = self.info.refined, []
        for ev, d in zip(self.res.events, result["events"], strict=True):
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
        """``key`` (v_cr or v_flutter) with its estimate, only if both runs' event is one."""
        name = self.info.refined
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
        out = with_estimate(result, key, refined, self.info.order, EVENT_TOL, ratio=self.info.ratio)
        out[key + REFINED] = fine_value
        return out

    def attach(self, result: dict, pipe) -> dict:
        """``result`` with every estimate and the ``"error_estimate"`` header."""
        res, fine_res = self.res, self.fine_res
        self.events(result)
        flutter = min(
            (e for e in res.events if e.branch == "primary" and e.type == "flutter"),
            key=lambda e: e.v,
            default=None,
        )
        for key, ev in (("v_cr", res.critical), ("v_flutter", flutter)):
            result = self.first(
                result, key, ev, None if fine_res is None else getattr(fine_res, key)
            )
        in_planes = hasattr(res, "in_plane")
        for plane in _PLANE_KEYS if in_planes else ():
            fine = None if fine_res is None else getattr(fine_res, plane).v_cr
            result = self.first(result, "v_cr_" + plane, getattr(res, plane).critical, fine)
        if result["critical"] is not None:
            result["critical"] = self.add(result["critical"], self.partner(res.critical))
        for plane in _PLANE_KEYS if in_planes else ():
            key = "critical_" + plane
            if result.get(key) is not None:
                result[key] = self.add(result[key], self.partner(getattr(res, plane).critical))
        if pipe is not None and "U_cr" in result:
            err, fine_v = result["v_cr" + ERROR], result["v_cr" + REFINED]
            extra = pair("U_cr", err, None, pipe.U_of_v(1.0))
            extra["U_cr" + REFINED] = None if fine_v is None else pipe.U_of_v(fine_v)
            result = beside(result, "U_cr", extra)
        result["error_estimate"] = header(self.info, self.notes)
        return result
