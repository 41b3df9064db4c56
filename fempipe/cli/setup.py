"""From parsed arguments to a validated problem: :func:`setup_from_args` and :class:`Setup`.

What depends on several options (the SI pipe, ``--U``, the variants of the
pipe, the work limits) is checked here, after argparse has checked each
option alone (:mod:`fempipe.cli.parsing`); bad input raises
:class:`~fempipe.cli.parsing.CLIError` naming the option, which the
dispatcher (:func:`fempipe.cli.main`) prints as one line, exit code 2.
The options themselves are declared in :mod:`fempipe.cli.common`.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass, replace

from fempipe.core.errors import ParamError
from fempipe.model.params import Params, PipeSI

from .parsing import (
    DEFAULT_BETA,
    DEFAULT_G,
    DEFAULT_GAMMA,
    DEFAULT_MU,
    END_MASS_MAX,
    MAX_DOFS,
    CLIError,
    ValueList,
    allow_large,
    check_count,
    check_si_groups,
    check_U,
    v_list_type,
)

__all__ = ["SI_OPTIONS", "Setup", "refuse_hysteretic", "setup_from_args"]

#: SI option -> PipeSI field.
SI_OPTIONS = {"--length": "L", "--EI": "EI", "--m": "m", "--M": "M", "--g": "g", "--a": "a"}
_SI_REQUIRED = ("--length", "--EI", "--m", "--M")
#: Params / PipeSI field -> the option that sets it, to name it in errors.
_DIMLESS_OPTION = {"alpha": "--alpha", "beta": "--beta", "gamma": "--gamma", "mu": "--mu"}
_SI_FIELD_OPTION = {field: opt for opt, field in SI_OPTIONS.items()} | {"alpha": "--alpha"}


@dataclass(frozen=True)
class Setup:
    """The validated problem behind a command line.

    Attributes
    ----------
    params : Params
        Dimensionless parameters; ``params.v`` is the first flow value (0 if none).
    pipe : PipeSI or None
        The SI pipe when SI input was given.
    v : list of float
        Dimensionless flow velocities (empty if the command has no flow list).
    disc : FiniteElement or Modal
    U : list of float or None
        The flow velocities in m/s as given by ``--U`` (or converted from ``--v``
        when the pipe is SI), else None.
    """

    params: Params
    pipe: PipeSI | None
    v: list[float]
    disc: object
    U: list[float] | None = None

    def to_dict(self) -> dict:
        """``params`` (with the ``pipe`` in SI when given) and ``discretization``."""
        p = self.params.to_dict()
        p.pop("v", None)
        out: dict = {"params": p, "discretization": self.disc.to_dict()}
        if self.pipe is not None:
            out["params"]["pipe_SI"] = self.pipe.to_dict()
            out["params"]["time_scale_s"] = self.pipe.time_scale
            out["params"]["velocity_scale_m_per_s"] = self.pipe.velocity_scale
        return out


def _given(args: argparse.Namespace, dest: str):
    return getattr(args, dest, None)


def setup_from_args(args: argparse.Namespace, need_flow: bool = True) -> Setup:
    """Turn parsed options into the validated :class:`Setup`.

    Parameters
    ----------
    args : argparse.Namespace
        From a parser with :func:`~fempipe.cli.common.add_physical_arguments`,
        :func:`~fempipe.cli.common.add_discretization_arguments` and optionally
        :func:`~fempipe.cli.common.add_flow_arguments`.
    need_flow : bool
        If False a missing flow list is allowed even without a default.

    Returns
    -------
    Setup

    Raises
    ------
    CLIError
        Naming the offending option; the dispatcher prints it and exits 2.
    """
    alpha = _given(args, "alpha")
    alpha = 0.0 if alpha is None else alpha
    large = allow_large(args)
    pipe, base = _pipe_from_args(args, alpha)
    base = _with_variants(args, base, pipe)
    v_list, U_list = _flow_from_args(args, pipe, large, need_flow)
    params = replace(base, v=v_list[0]) if v_list else base
    disc = _discretization_from_args(args, large)
    if pipe is not None and _given(args, "a") is None:
        # The two ways of giving the pipe differ in one default: every such run says so
        # (fempipe.cli.main prints the notices when the command has run).
        notices = args.__dict__.setdefault("_notices", [])
        notices.append(
            "the SI pipe has no Kelvin-Voigt damping unless --a is given "
            f"(mu = 0 here; a dimensionless run takes the paper's mu = {DEFAULT_MU:g})"
        )
    return Setup(params=params, pipe=pipe, v=v_list, disc=disc, U=U_list)


def _pipe_from_args(args: argparse.Namespace, alpha: float) -> tuple[PipeSI | None, Params]:
    """``(pipe, params at v = 0)``: the SI pipe, or the dimensionless groups (pipe None)."""
    si_given = [opt for opt in SI_OPTIONS if _given(args, opt[2:]) is not None]
    if not si_given:
        vals = {"alpha": alpha, "beta": DEFAULT_BETA, "gamma": DEFAULT_GAMMA, "mu": DEFAULT_MU}
        for name in ("beta", "gamma", "mu"):
            if _given(args, name) is not None:
                vals[name] = _given(args, name)
        try:
            return None, Params(**vals)
        except ParamError as exc:
            raise CLIError(_DIMLESS_OPTION[exc.field], str(exc)) from None
    missing = [opt for opt in _SI_REQUIRED if _given(args, opt[2:]) is None]
    if missing:
        # Blame the option that asked for the SI pipe when none of the
        # required ones was given (--g 9.8 alone), else the first missing.
        named = missing[0] if len(missing) < len(_SI_REQUIRED) else si_given[0]
        raise CLIError(
            named,
            f"the SI pipe needs {' '.join(_SI_REQUIRED)} together; missing {' '.join(missing)}",
        )
    for opt in ("--beta", "--gamma", "--mu"):
        if _given(args, opt[2:]) is not None:
            raise CLIError(
                opt,
                f"cannot be combined with the SI pipe ({si_given[0]}): "
                "beta, gamma, mu follow from --length --EI --m --M --g --a",
            )
    kw = {f: _given(args, opt[2:]) for opt, f in SI_OPTIONS.items()}
    kw = {f: x for f, x in kw.items() if x is not None}
    kw.setdefault("g", DEFAULT_G)
    try:
        pipe = PipeSI(alpha=alpha, **kw)
    except ParamError as exc:
        raise CLIError(_SI_FIELD_OPTION[exc.field], str(exc)) from None
    base = pipe.params(0.0)
    check_si_groups(base)
    return pipe, base


def _flow_from_args(
    args: argparse.Namespace, pipe: PipeSI | None, large: bool, need_flow: bool
) -> tuple[list[float], list[float] | None]:
    """``(v, U)``: the flow velocities, dimensionless and in m/s (None without an SI pipe)."""
    v_list: list[float] = []
    U_list: list[float] | None = None
    if _given(args, "U") is not None:
        if pipe is None:
            raise CLIError(
                "--U",
                "needs the SI pipe (--length --EI --m --M); use --v for dimensionless flow",
            )
        U_spec: ValueList = args.U
        check_U(pipe, U_spec)
        U_list = U_spec.values(large)
        v_list = [pipe.v_of_U(U) for U in U_list]
        return v_list, U_list
    spec = _given(args, "v")
    if spec is None and getattr(args, "_flow_default", None) is not None:
        spec = v_list_type(args._flow_default)
    if spec is not None:
        v_list = spec.values(large)
    elif need_flow and hasattr(args, "_flow_default"):
        raise CLIError("--v", "give the flow velocities (--v or --U)")
    if pipe is not None and v_list:
        U_list = [pipe.U_of_v(v) for v in v_list]
    return v_list, U_list


def _discretization_from_args(args: argparse.Namespace, large: bool):
    """``--fe`` or ``--modal`` (with ``--basis``), within the unknowns' work limit."""
    from fempipe.model.discretization import parse_discretization

    fe, modal = _given(args, "fe"), _given(args, "modal")
    basis = _given(args, "basis") or "sine"
    if basis != "sine" and modal is None:
        raise CLIError(
            "--basis",
            f"{basis} chooses the modes of --modal N and needs it"
            + (" (finite elements --fe have no basis)" if fe is not None else ""),
        )
    option, (text, unknowns) = (
        ("--modal", modal) if modal is not None else ("--fe", fe or (None, 0))
    )
    check_count(option, unknowns, MAX_DOFS, large, "unknowns")
    try:
        return parse_discretization(
            fe=None if fe is None else fe[0],
            modal=None if modal is None else modal[0],
            basis=basis,
        )
    except ValueError as exc:
        raise CLIError(option, str(exc)) from None


def _with_variants(args: argparse.Namespace, base: Params, pipe: PipeSI | None) -> Params:
    """``base`` with the end mass, dampings and springs of the command line."""
    end_mass = _given(args, "end_mass")
    end_mass_kg = _given(args, "end_mass_kg")
    if end_mass_kg is not None:
        if pipe is None:
            raise CLIError(
                "--end-mass-kg",
                "needs the SI pipe (--length --EI --m --M); use "
                "--end-mass for the dimensionless Gamma = M_e / ((m+M) L)",
            )
        if end_mass is not None:
            raise CLIError("--end-mass-kg", "give --end-mass or --end-mass-kg, not both")
        end_mass = pipe.end_mass_ratio(end_mass_kg)
        if end_mass > END_MASS_MAX:
            raise CLIError(
                "--end-mass-kg",
                f"M_e = {end_mass_kg:g} kg is Gamma = {end_mass:.6g} > {END_MASS_MAX:g} times "
                "the pipe's mass",
            )
    kw = {
        "end_mass": end_mass,
        "external_damping": _given(args, "external_damping"),
        "hysteretic_damping": _given(args, "hysteretic_damping"),
        "springs": tuple(_given(args, "spring") or ()) or None,
    }
    kw = {k: x for k, x in kw.items() if x is not None}
    if not kw:
        return base
    try:
        return replace(base, **kw)
    except ParamError as exc:
        raise CLIError(_VARIANT_OPTION.get(exc.field, "--" + exc.field), str(exc)) from None


_VARIANT_OPTION = {
    "end_mass": "--end-mass",
    "external_damping": "--external-damping",
    "hysteretic_damping": "--hysteretic-damping",
    "springs": "--spring",
}


def refuse_hysteretic(args: argparse.Namespace, command: str) -> None:
    """Time-domain commands: hysteretic damping has no meaning there (one-line error)."""
    if _given(args, "hysteretic_damping"):
        raise CLIError(
            "--hysteretic-damping",
            f"has no time-domain meaning (EI (1 + i mu_h) acts on harmonic motion only); "
            f"{command} cannot use it: use spectrum, critical or stability-map",
        )
