"""The Hopf normal forms of the flutter events of a stability analysis.

The static state at each flutter event is reconstructed
(:func:`event_states`), its normal form computed (:func:`normal_forms`) and
added to the events of ``fempipe critical --json`` (:func:`decorate_events`,
:data:`EVENT_KEYS`).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from fempipe.analyses.statics import NewtonError, solve_path
from fempipe.core.parallel import single_blas
from fempipe.model.plane.operators import PipeModel

from ..linear import straight_is_static
from .normal_form import HopfNormalForm, first_lyapunov_coefficient

#: Keys added to every flutter event of ``fempipe critical --json``.
EVENT_KEYS = (
    "first_lyapunov_coefficient",
    "first_lyapunov_uncertainty",
    "criticality",
    "transversality",
    "cycle_side",
    "theta_tip_amplitude_coefficient",
    "eta_tip_amplitude_coefficient",
    "Y_tip_amplitude_coefficient",
    "hopf_note",
)
#: The eigenvalue at the reconstructed state must be within this (relative to
#: max(1, |lambda|)) of the event's to accept the state as the event's.
STATE_MATCH_TOL = 1e-6
#: Largest step in v of the static path to the flutter points.
PATH_STEP = 1.0


def _key(ev) -> tuple:
    return (ev.branch, ev.type, float(ev.v), ev.mode)


def event_states(model: PipeModel, result) -> dict:
    """Static states at the flutter events of a :class:`~fempipe.analyses.stability.StabilityResult`.

    ``{(branch, type, v, mode): q or reason}``: the primary branch followed again from its start
    in steps of at most :data:`PATH_STEP`; a reason for other branches and for instabilities
    present at the start.
    """
    out: dict = {}
    flutter = [ev for ev in result.events if ev.type == "flutter"]
    primary = sorted(
        (ev for ev in flutter if ev.branch == "primary" and not ev.at_start), key=lambda e: e.v
    )
    for ev in flutter:
        if ev.at_start:
            out[_key(ev)] = "an instability present at the start of the range, not a crossing"
        elif ev.branch != "primary":
            out[_key(ev)] = f"the static state of branch {ev.branch} is not reconstructed"
    if not primary:
        return out
    v_lo = float(result.v_range[0])
    targets = sorted({float(ev.v) for ev in primary})
    values = [v_lo]
    for vt in targets:
        k = max(1, math.ceil((vt - values[-1]) / PATH_STEP))
        values.extend(np.linspace(values[-1], vt, k + 1)[1:].tolist())
        values[-1] = vt
    try:
        sols = solve_path(model.with_params(replace(model.params, v=v_lo)), values)
    except NewtonError as exc:
        for ev in primary:
            out[_key(ev)] = f"the static state was not found on the way to v = {ev.v:.10g} ({exc})"
        return out
    states = {v: sol.q for v, sol in zip(values, sols, strict=True)}
    for ev in primary:
        out[_key(ev)] = states[float(ev.v)]
    return out


@single_blas
def normal_forms(model: PipeModel, result) -> dict:
    """``{(branch, type, v, mode): HopfNormalForm or reason}`` of ``result``'s flutter events."""
    if model.params.hysteretic_damping > 0.0:
        reason = "hysteretic damping is a frequency-domain model without an equation of motion"
        return {_key(ev): reason for ev in result.events if ev.type == "flutter"}
    out = {}
    if straight_is_static(model.params):
        # The straight pipe is a static state at every v (alpha = 0 or pi); when
        # it carries the event's eigenvalue no path needs to be followed.
        for ev in result.events:
            if ev.type == "flutter" and ev.branch == "primary" and not ev.at_start:
                nf = _normal_form(model, result, _key(ev), np.zeros(model.n))
                if not isinstance(nf, str):
                    out[_key(ev)] = nf
    states = None
    for ev in result.events:
        key = _key(ev)
        if ev.type != "flutter" or key in out:
            continue
        if states is None:
            states = event_states(model, result)
        q = states[key]
        out[key] = q if isinstance(q, str) else _normal_form(model, result, key, q)
    return out


def _normal_form(model: PipeModel, result, key: tuple, q: np.ndarray) -> HopfNormalForm | str:
    """The normal form at the event ``key`` from the static state q, or why there is none."""
    m = model.with_params(replace(model.params, v=key[2]))
    ev = next(e for e in result.events if _key(e) == key)
    try:
        nf = first_lyapunov_coefficient(m, q, omega=float(ev.frequency))
    except (ValueError, np.linalg.LinAlgError) as exc:
        return f"no normal form: {exc}"
    # The state is the event's if its critical eigenvalue is the event's.
    target = complex(ev.eigenvalue)
    err = abs(nf.eigenvalue - target) / max(1.0, abs(target))
    if err <= STATE_MATCH_TOL:
        return nf
    return (
        f"the static state reconstructed at v = {ev.v:.10g} does not hold the event's "
        f"eigenvalue (relative distance {err:.2g})"
    )


#: The keys of an out-of-plane flutter the 3-D normal form is not computed for.
_NOT_PRIMARY = dict.fromkeys(EVENT_KEYS) | {
    "hopf_note": "the 3-D normal form is computed for the primary branch's events"
}


def decorate_events(
    result_dict: dict, model: PipeModel, result, out_of_plane: dict | None = None
) -> dict:
    """Add :data:`EVENT_KEYS` to the flutter events of ``fempipe critical --json`` (in place).

    ``hopf_note`` is null, or why the other keys are; the flutters out of the plane take their
    keys from ``out_of_plane``, ``{(branch, v): keys}``
    (:func:`fempipe.analyses.three_d.onset.out_of_plane_event_keys`).
    """
    forms = normal_forms(model, result)
    out_of_plane = out_of_plane or {}

    def decorate(d: dict | None) -> None:
        if d is None or d.get("type") != "flutter":
            return
        if d.get("plane", "in") != "in":
            # the 3-D model's normal form (fempipe.analyses.three_d.onset.out_of_plane_event_keys)
            d.update(out_of_plane.get((d["branch"], float(d["v"])), _NOT_PRIMARY))
            return
        key = (d["branch"], d["type"], float(d["v"]), d["mode"])
        nf = forms.get(key, "no normal form computed for this event")
        if isinstance(nf, str):
            d.update(dict.fromkeys(EVENT_KEYS))
            d["hopf_note"] = nf
        else:
            d.update(nf.event_keys())  # a planar cycle: Y_tip_amplitude_coefficient null

    for d in result_dict.get("events", []):
        decorate(d)
    decorate(result_dict.get("critical"))
    for key in ("critical_in_plane", "critical_out_of_plane"):
        decorate(result_dict.get(key))
    for b in result_dict.get("branches", []) + result_dict.get("branches_out_of_plane", []):
        for d in b.get("events", []):
            decorate(d)
    return result_dict
