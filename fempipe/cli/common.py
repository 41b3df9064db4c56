"""The one option parser shared by every ``fempipe`` subcommand.

Every subcommand that solves the pipe takes the same physical parameters,
discretisation, flow values and output options; they are declared here once
so that the spellings (``--alpha 90deg``, ``--fe P3:16``, ``--v 0:6:13``,
``--U 0,0.5,1``) and the error messages are the same everywhere.

Physical parameters come either dimensionless (``--alpha --beta --gamma
--mu``, with ``--v`` for the flow) or in SI units (``--length --EI --m --M``,
all four together, plus optional ``--g --a``, with ``--U`` in m/s for the
flow), Eq. (19) of Chen, Hu, Dai & Wang (2020).

Bad input is refused before any computation, with one line naming the
option: a single option is checked by its argparse ``type=`` callable
(:mod:`fempipe.cli.parsing`, which also states the accepted ranges and the
work limits and why), what depends on several options (the SI pipe, ``--U``,
the work limits) by :func:`setup_from_args`, which raises
:class:`~fempipe.cli.parsing.CLIError`.  The dispatcher
(:func:`fempipe.cli.main`) prints ``fempipe <cmd>: error: --option: message``
on stderr and exits with code 2.

Typical use in a subcommand module::

    def add_arguments(parser):
        common.add_physical_arguments(parser)
        common.add_flow_arguments(parser, default="0:10:11")
        common.add_discretization_arguments(parser)
        common.add_output_arguments(parser)

    def run(args):
        setup = common.setup_from_args(args)   # raises CLIError on bad input
        model = PipeModel(setup.disc, setup.params)   # setup.v: the flow values
"""

from __future__ import annotations

import argparse
import re
from dataclasses import dataclass, replace

from fempipe.core.errors import ParamError
from fempipe.model.params import Params, PipeSI

from .parsing import (
    DEFAULT_BETA,
    DEFAULT_G,
    DEFAULT_GAMMA,
    DEFAULT_MU,
    END_MASS_MAX,
    EXTERNAL_DAMPING_MAX,
    GAMMA_MAX,
    HYSTERETIC_MAX,
    MAX_DOFS,
    MAX_VALUES,
    MU_MAX,
    SPRING_MAX,
    T_MAX,
    V_MAX,
    CLIError,
    U_list_type,
    ValueList,
    allow_large,
    alpha_type,
    beta_type,
    check_count,
    check_si_groups,
    check_U,
    fe_type,
    gamma_type,
    modal_type,
    mu_type,
    number_type,
    spring_type,
    v_list_type,
    workers_type,
)

__all__ = [
    "ArgumentParser",
    "Setup",
    "add_discretization_arguments",
    "add_flow_arguments",
    "add_output_arguments",
    "add_physical_arguments",
    "setup_from_args",
]

#: SI option -> PipeSI field.
_SI_OPTIONS = {"--length": "L", "--EI": "EI", "--m": "m", "--M": "M", "--g": "g", "--a": "a"}
_SI_REQUIRED = ("--length", "--EI", "--m", "--M")
#: Params / PipeSI field -> the option that sets it, to name it in errors.
_DIMLESS_OPTION = {"alpha": "--alpha", "beta": "--beta", "gamma": "--gamma", "mu": "--mu"}
_SI_FIELD_OPTION = {field: opt for opt, field in _SI_OPTIONS.items()} | {"alpha": "--alpha"}


class ArgumentParser(argparse.ArgumentParser):
    """argparse with one-line errors: ``prog: error: message`` and exit code 2.

    The standard parser prints the whole usage block before the error; the
    project's rule is one line naming the option (``--help`` still shows usage).
    """

    def error(self, message: str):  # noqa: D102 - argparse API
        message = " ".join(message.split())
        # A type= callable's error reads "argument --v: ..."; print "--v: ...",
        # like CLIError.
        message = re.sub(r"^argument (-[-\w]+)(?:/-[-\w]+)?: ", r"\1: ", message)
        self.exit(2, f"{self.prog}: error: {message}\n")


# ---------------------------------------------------------------------------
# Option groups
# ---------------------------------------------------------------------------


def add_physical_arguments(parser: argparse.ArgumentParser, alpha: bool = True) -> None:
    """Dimensionless ``--alpha --beta --gamma --mu`` or SI ``--length --EI --m --M --g --a``.

    With ``alpha=False`` (a command with its own list of inclinations)
    ``--alpha`` is not shown in ``--help``; the command refuses it.

    Each value is checked on its own by its ``type=``; the SI pipe as a whole
    by :func:`setup_from_args`.
    """
    g = parser.add_argument_group(
        "physical parameters",
        f"dimensionless (Eq. (19)); defaults are the paper's case beta={DEFAULT_BETA:g}, "
        f"gamma={DEFAULT_GAMMA:g}, mu={DEFAULT_MU:g}, alpha=0. Give SI values instead to have "
        "beta, gamma, mu computed. Accepted: gamma <= 2500 and v <= 50, where the clamp layer "
        "(width 1/sqrt(gamma)) and the bending waves of the flow (length 1/v) are as narrow as "
        "the node spacing 1/48 of the default mesh P3:16; mu <= 10 (every mode is overdamped "
        "from mu = 0.57 on).",
    )
    g.add_argument(
        "--alpha",
        metavar="A",
        type=alpha_type,
        default=None,
        help="inclination from the downward vertical, -2pi..2pi: radians (1.5708), degrees "
        "(90deg) or a multiple of pi (pi/2, 0.5pi, 3pi/4); negative values as --alpha=-pi/4 "
        "(default 0; pi stands up)"
        if alpha
        else argparse.SUPPRESS,
    )
    g.add_argument(
        "--beta",
        metavar="B",
        type=beta_type,
        default=None,
        help="mass ratio M/(m+M) in [0, 1]",
    )
    g.add_argument(
        "--gamma",
        metavar="G",
        type=gamma_type,
        default=None,
        help=f"gravity (m+M) g L^3/EI, 0..{GAMMA_MAX:g} (a standing pipe is --alpha pi, not "
        "gamma < 0)",
    )
    g.add_argument(
        "--mu",
        metavar="MU",
        type=mu_type,
        default=None,
        help=f"Kelvin-Voigt damping, 0..{MU_MAX:g}",
    )
    si = parser.add_argument_group(
        "SI pipe (instead of --beta --gamma --mu)",
        "--length --EI --m --M are required together; the flow is then given by --U in m/s. "
        "The pipe's gamma and mu must lie in the ranges above.",
    )
    for opt, metavar, text in (
        ("--length", "L", "pipe length, m"),
        ("--EI", "EI", "bending stiffness, N m^2"),
        ("--m", "m", "pipe mass per length, kg/m"),
        ("--M", "M", "fluid mass per length, kg/m"),
        ("--g", "g", f"gravity, m/s^2 (default {DEFAULT_G:g})"),
        ("--a", "a", "Kelvin-Voigt retardation time, s (default 0)"),
    ):
        si.add_argument(opt, metavar=metavar, type=number_type(opt), default=None, help=text)
    si.add_argument(
        "--end-mass-kg",
        metavar="KG",
        type=number_type("--end-mass-kg", 0.0),
        default=None,
        help="point mass at the free end, kg (sets --end-mass = M_e / ((m+M) L))",
    )
    add_variant_arguments(parser)


def add_variant_arguments(parser: argparse.ArgumentParser) -> None:
    """``--end-mass``, ``--external-damping``, ``--hysteretic-damping``, ``--spring``."""
    g = parser.add_argument_group(
        "variants of the pipe",
        "dimensionless, scaled as Eq. (19); all zero is the paper's pipe",
    )
    g.add_argument(
        "--end-mass",
        metavar="GAMMA_E",
        type=number_type("--end-mass", 0.0, END_MASS_MAX),
        default=None,
        help=f"point mass at the free end over the pipe's mass, M_e/((m+M) L), 0..{END_MASS_MAX:g}",
    )
    g.add_argument(
        "--external-damping",
        metavar="SIGMA",
        type=number_type("--external-damping", 0.0, EXTERNAL_DAMPING_MAX),
        default=None,
        help="viscous damping by the surrounding fluid, a force -c r_dot per length: "
        f"sigma = c L^2 / sqrt(EI (m+M)), 0..{EXTERNAL_DAMPING_MAX:g}",
    )
    g.add_argument(
        "--hysteretic-damping",
        metavar="MU_H",
        type=number_type("--hysteretic-damping", 0.0, HYSTERETIC_MAX),
        default=None,
        help="structural loss factor, EI -> EI (1 + i MU_H sgn(omega)) in the linear stability "
        f"problem only (spectrum, critical, stability-map), 0..{HYSTERETIC_MAX:g}",
    )
    g.add_argument(
        "--spring",
        metavar="KAPPA@XI_S",
        action="append",
        type=spring_type,
        default=None,
        help="linear spring tying the point xi_s (0 < XI_S <= 1) to its undeformed position, "
        f"kappa = k L^3 / EI, 0..{SPRING_MAX:g}; repeat for several springs",
    )


def add_flow_arguments(parser: argparse.ArgumentParser, default: str | None = "0:10:11") -> None:
    """``--v`` (dimensionless) or ``--U`` (m/s, with an SI pipe): lists or ranges.

    Parameters
    ----------
    default : str or None
        Default for ``--v`` (used when neither is given); None makes the flow
        optional (``Setup.v`` is then empty).
    """
    g = parser.add_argument_group("flow velocity")
    ex = g.add_mutually_exclusive_group()
    d = f" (default {default})" if default is not None else ""
    ex.add_argument(
        "--v",
        metavar="LIST",
        type=v_list_type,
        default=None,
        help=f"dimensionless flow velocities, 0..{V_MAX:g}: 0,2,4 or start:stop:count like "
        f"0:6:13{d}",
    )
    ex.add_argument(
        "--U",
        metavar="LIST",
        type=U_list_type,
        default=None,
        help="flow velocities in m/s (needs the SI pipe; up to the U of v = "
        f"{V_MAX:g}): 0,0.5,1 or 0:3:7",
    )
    parser.set_defaults(_flow_default=default)


def add_discretization_arguments(parser: argparse.ArgumentParser) -> None:
    """``--fe Pk:n`` (default :data:`~fempipe.model.discretization.DEFAULT_FE`) or ``--modal N``
    with ``--basis sine|beam``, and ``--allow-large``."""
    # Imported here: ``fempipe --help`` does not need numpy.
    from fempipe.model.discretization import DEFAULT_FE, Modal

    g = parser.add_argument_group("discretisation and work limits")
    ex = g.add_mutually_exclusive_group()
    ex.add_argument(
        "--fe",
        metavar="Pk:n",
        type=fe_type,
        default=None,
        help=f"Lagrange elements of degree k (1..10) on n uniform elements (default {DEFAULT_FE})",
    )
    ex.add_argument(
        "--modal",
        metavar="N",
        type=modal_type,
        default=None,
        help="N global modes instead of finite elements: the paper's sine modes "
        "sin((2r-1) pi xi/2), or with --basis beam the slopes of the clamped-free beam modes",
    )
    g.add_argument(
        "--basis",
        choices=Modal.BASES,
        default="sine",
        help="the modes of --modal: sine (the paper's, Eq. (22); error ~ N^-3) or beam "
        "(clamped-free Euler-Bernoulli beam modes; error ~ N^-4); default sine",
    )
    g.add_argument(
        "--allow-large",
        action="store_true",
        help=f"accept more than {MAX_DOFS} unknowns (n k of Pk:n, N of --modal), lists of more "
        f"than {MAX_VALUES} values (or points of a map or sweep) and --t-max above {T_MAX:g}",
    )


def add_integration_arguments(
    parser: argparse.ArgumentParser,
    *,
    shoot_rtol: str,
    shoot_help: str,
    group=None,
    per: str = "in tau",
):
    """``--t-max``, ``--rtol``, ``--shoot-rtol``: the time integration of ``simulate`` and ``bifurcation``.

    Returns the argument group (``group`` if given, else a new "time
    integration" group) so that a subcommand can add its own options to it.
    """
    g = group if group is not None else parser.add_argument_group("time integration")
    num = number_type
    g.add_argument(
        "--t-max",
        metavar="T",
        type=num("--t-max", 0.0, strict_low=True),
        default="300",
        help=f"longest integration {per} (300; above {T_MAX:g} needs --allow-large)",
    )
    g.add_argument(
        "--rtol",
        metavar="TOL",
        type=num("--rtol", 0.0, 0.1, strict_low=True),
        default="1e-5",
        help="tolerance of the transient (1e-5)",
    )
    g.add_argument(
        "--shoot-rtol",
        metavar="TOL",
        type=num("--shoot-rtol", 0.0, 0.1, strict_low=True),
        default=shoot_rtol,
        help=f"{shoot_help} ({shoot_rtol})",
    )
    return g


def add_workers_argument(group, help: str, default: str | None = "1") -> None:
    """``--workers N`` (a positive integer) in ``group`` (a parser or an argument group)."""
    group.add_argument("--workers", metavar="N", type=workers_type, default=default, help=help)


def add_shoot_rtol_argument(group, help: str, default: str = "1e-9") -> None:
    """``--shoot-rtol TOL``: the integration tolerance of a limit cycle's shooting."""
    group.add_argument(
        "--shoot-rtol",
        metavar="TOL",
        type=number_type("--shoot-rtol", 0.0, 0.1, strict_low=True),
        default=default,
        help=f"{help} ({default})",
    )


def add_planar_argument(group, what: str) -> None:
    """``--planar``: the paper's planar model alone, every output as before the
    out-of-plane analysis existed (as ``fempipe critical --planar``).

    ``what`` says what changes, e.g. "stable is the in-plane verdict".
    """
    group.add_argument(
        "--planar",
        action="store_true",
        help="the paper's planar model only: no analysis of the motion out of the plane "
        f"({what}, every output as before)",
    )


def add_output_arguments(parser: argparse.ArgumentParser, out_help: str | None = None) -> None:
    """``--json``, ``--out DIR`` and ``--quiet`` / ``--progress``.

    Parameters
    ----------
    out_help : str, optional
        Help of ``--out`` (default: "write result files into DIR").
    """
    g = parser.add_argument_group("output")
    g.add_argument(
        "--json",
        action="store_true",
        help="print machine-readable JSON on stdout (and nothing else there)",
    )
    g.add_argument(
        "--out", metavar="DIR", default=None, help=out_help or "write result files into DIR"
    )
    ex = g.add_mutually_exclusive_group()
    ex.add_argument(
        "--progress",
        dest="progress",
        action="store_true",
        default=None,
        help="show a progress bar on stderr (default: when stderr is a terminal)",
    )
    ex.add_argument(
        "--quiet", dest="progress", action="store_false", help="no progress bar, no log output"
    )


# ---------------------------------------------------------------------------
# From parsed arguments to a validated problem
# ---------------------------------------------------------------------------


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
        From a parser with :func:`add_physical_arguments`,
        :func:`add_discretization_arguments` and optionally
        :func:`add_flow_arguments`.
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
    from fempipe.model.discretization import parse_discretization

    alpha = _given(args, "alpha")
    alpha = 0.0 if alpha is None else alpha
    large = allow_large(args)

    # --- SI pipe or dimensionless groups ------------------------------
    si_given = [opt for opt in _SI_OPTIONS if _given(args, opt[2:]) is not None]
    pipe: PipeSI | None = None
    if si_given:
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
        kw = {f: _given(args, opt[2:]) for opt, f in _SI_OPTIONS.items()}
        kw = {f: x for f, x in kw.items() if x is not None}
        kw.setdefault("g", DEFAULT_G)
        try:
            pipe = PipeSI(alpha=alpha, **kw)
        except ParamError as exc:
            raise CLIError(_SI_FIELD_OPTION[exc.field], str(exc)) from None
        base = pipe.params(0.0)
        check_si_groups(base)
    else:
        vals = {"alpha": alpha, "beta": DEFAULT_BETA, "gamma": DEFAULT_GAMMA, "mu": DEFAULT_MU}
        for name in ("beta", "gamma", "mu"):
            if _given(args, name) is not None:
                vals[name] = _given(args, name)
        try:
            base = Params(**vals)
        except ParamError as exc:
            raise CLIError(_DIMLESS_OPTION[exc.field], str(exc)) from None

    # --- variants of the pipe -----------------------------------------
    base = _with_variants(args, base, pipe)

    # --- flow ---------------------------------------------------------
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
    else:
        spec = _given(args, "v")
        if spec is None and getattr(args, "_flow_default", None) is not None:
            spec = v_list_type(args._flow_default)
        if spec is not None:
            v_list = spec.values(large)
        elif need_flow and hasattr(args, "_flow_default"):
            raise CLIError("--v", "give the flow velocities (--v or --U)")
        if pipe is not None and v_list:
            U_list = [pipe.U_of_v(v) for v in v_list]
    params = replace(base, v=v_list[0]) if v_list else base

    # --- discretisation -----------------------------------------------
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
        disc = parse_discretization(
            fe=None if fe is None else fe[0],
            modal=None if modal is None else modal[0],
            basis=basis,
        )
    except ValueError as exc:
        raise CLIError(option, str(exc)) from None

    return Setup(params=params, pipe=pipe, v=v_list, disc=disc, U=U_list)


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
