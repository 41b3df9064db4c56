"""The options shared by the ``fempipe`` subcommands, declared once, and :func:`setup_from_args`.

Parameters dimensionless (``--alpha --beta --gamma --mu``, ``--v``) or SI (``--length --EI --m
--M``, ``--g --a``, ``--U`` in m/s), Eq. (19).  argparse checks each option alone
(:mod:`fempipe.cli.parsing`); :func:`setup_from_args` what depends on several (CLIError).  The
options: docs/cli/options.md.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass, replace

from fempipe.core.errors import ParamError
from fempipe.io import ranges
from fempipe.io.ranges import DEFAULT_BETA, DEFAULT_G, DEFAULT_GAMMA, DEFAULT_MU, GAMMA_MAX, MU_MAX
from fempipe.model.params import Params, PipeSI

from . import parsing
from .parsing import CLIError

__all__ = [
    "Setup",
    "add_problem_arguments",
    "number",
    "option",
    "add_discretization_arguments",
    "add_error_estimate_argument",
    "add_flow_arguments",
    "add_integration_arguments",
    "add_output_arguments",
    "add_physical_arguments",
    "add_planar_argument",
    "add_shoot_rtol_argument",
    "add_workers_argument",
    "flow_option",
    "refuse_hysteretic",
    "setup_from_args",
]


def add_problem_arguments(
    parser: argparse.ArgumentParser, flow: str | None, alpha: bool = True
) -> None:
    """The physical, flow (default ``flow``) and discretization arguments."""
    add_physical_arguments(parser, alpha)
    add_flow_arguments(parser, flow)
    add_discretization_arguments(parser)


def option(group, name: str, metavar: str, parse, default, help: str, **kw) -> None:
    """``name`` whose value ``parse(text)`` checks (its ValueError a usage error naming it)."""
    type_ = parsing.option_type(name, parse)
    group.add_argument(name, metavar=metavar, type=type_, default=default, help=help, **kw)


def number(group, name: str, metavar: str, default, help: str, *bounds, strict_low=False) -> None:
    """``name``, a finite number within ``bounds`` (low, high: :func:`parsing.number_type`)."""
    type_ = parsing.number_type(name, *bounds, strict_low=strict_low)
    group.add_argument(name, metavar=metavar, type=type_, default=default, help=help)


def add_physical_arguments(parser: argparse.ArgumentParser, alpha: bool = True) -> None:
    """The dimensionless groups, the SI pipe and the variants of the pipe; with ``alpha=False``
    (a command with its own list of inclinations) ``--alpha`` is hidden and refused."""
    g = parser.add_argument_group(
        "physical parameters",
        f"dimensionless (Eq. (19)); defaults are the paper's case beta={DEFAULT_BETA:g}, "
        f"gamma={DEFAULT_GAMMA:g}, mu={DEFAULT_MU:g}, alpha=0. Give SI values instead to have "
        "beta, gamma, mu computed. Accepted: gamma <= 2500 and v <= 50, where the clamp layer "
        "(width 1/sqrt(gamma)) and the bending waves of the flow (length 1/v) are as narrow as "
        "the node spacing 1/48 of the default mesh P3:16; mu <= 10 (every mode is overdamped "
        "from mu = 0.57 on).",
    )
    alpha_help = (
        "inclination from the downward vertical, -2pi..2pi: radians (1.5708), degrees (90deg) "
        "or a multiple of pi (pi/2, 0.5pi, 3pi/4); negative values as --alpha=-pi/4 (default 0; "
        "pi stands up)"
    )
    for opt, metavar, type_, text in (
        ("--alpha", "A", parsing.alpha_type, alpha_help if alpha else argparse.SUPPRESS),
        ("--beta", "B", parsing.beta_type, "mass ratio M/(m+M) in [0, 1]"),
        (
            "--gamma",
            "G",
            parsing.gamma_type,
            f"gravity (m+M) g L^3/EI, 0..{GAMMA_MAX:g} (a standing pipe is --alpha pi, not "
            "gamma < 0)",
        ),
        ("--mu", "MU", parsing.mu_type, f"Kelvin-Voigt damping, 0..{MU_MAX:g}"),
    ):
        g.add_argument(opt, metavar=metavar, type=type_, default=None, help=text)
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
        si.add_argument(
            opt, metavar=metavar, type=parsing.number_type(opt), default=None, help=text
        )
    si.add_argument(
        "--end-mass-kg",
        metavar="KG",
        type=parsing.number_type("--end-mass-kg", 0.0),
        default=None,
        help="point mass at the free end, kg (sets --end-mass = M_e / ((m+M) L))",
    )
    g = parser.add_argument_group(
        "variants of the pipe", "dimensionless, scaled as Eq. (19); all zero is the paper's pipe"
    )
    for opt, metavar, high, text in (
        (
            "--end-mass",
            "GAMMA_E",
            parsing.END_MASS_MAX,
            "point mass at the free end over the pipe's mass, M_e/((m+M) L)",
        ),
        (
            "--external-damping",
            "SIGMA",
            parsing.EXTERNAL_DAMPING_MAX,
            "viscous damping by the surrounding fluid, a force -c r_dot per length: "
            "sigma = c L^2 / sqrt(EI (m+M))",
        ),
        (
            "--hysteretic-damping",
            "MU_H",
            parsing.HYSTERETIC_MAX,
            "structural loss factor, EI -> EI (1 + i MU_H sgn(omega)) in the linear stability "
            "problem only (spectrum, critical, stability-map)",
        ),
    ):
        type_ = parsing.number_type(opt, 0.0, high)
        g.add_argument(opt, metavar=metavar, type=type_, default=None, help=f"{text}, 0..{high:g}")
    g.add_argument(
        "--spring",
        metavar="KAPPA@XI_S",
        action="append",
        type=parsing.spring_type,
        default=None,
        help="linear spring tying the point xi_s (0 < XI_S <= 1) to its undeformed position, "
        f"kappa = k L^3 / EI, 0..{parsing.SPRING_MAX:g}; repeat for several springs",
    )


def add_flow_arguments(parser: argparse.ArgumentParser, default: str | None = "0:10:11") -> None:
    """``--v`` or ``--U`` (lists or ranges); ``default`` of ``--v``, None: the flow is optional."""
    ex = parser.add_argument_group("flow velocity").add_mutually_exclusive_group()
    d = f" (default {default})" if default is not None else ""
    ex.add_argument(
        "--v",
        metavar="LIST",
        type=parsing.v_list_type,
        default=None,
        help=f"dimensionless flow velocities, 0..{ranges.V_MAX:g}: 0,2,4 or start:stop:count "
        f"like 0:6:13{d}",
    )
    ex.add_argument(
        "--U",
        metavar="LIST",
        type=parsing.U_list_type,
        default=None,
        help="flow velocities in m/s (needs the SI pipe; up to the U of v = "
        f"{ranges.V_MAX:g}): 0,0.5,1 or 0:3:7",
    )
    parser.set_defaults(_flow_default=default)


def add_discretization_arguments(parser: argparse.ArgumentParser) -> None:
    """``--fe Pk:n`` or ``--modal N`` with ``--basis``, and ``--allow-large``."""
    from fempipe.model.discretization import DEFAULT_FE, Modal  # numpy: not for `fempipe --help`

    g = parser.add_argument_group("discretization and work limits")
    ex = g.add_mutually_exclusive_group()
    ex.add_argument(
        "--fe",
        metavar="Pk:n",
        type=parsing.fe_type,
        default=None,
        help=f"Lagrange elements of degree k (1..10) on n uniform elements (default {DEFAULT_FE})",
    )
    ex.add_argument(
        "--modal",
        metavar="N",
        type=parsing.modal_type,
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
    add_allow_large_argument(
        g,
        f"accept more than {parsing.MAX_DOFS} unknowns (n k of Pk:n, N of --modal), lists of more "
        f"than {parsing.MAX_VALUES} values (or points of a map or sweep) and --t-max above "
        f"{parsing.T_MAX:g}",
    )


def add_allow_large_argument(group, help: str) -> None:
    """``--allow-large``: lift the work limits of :mod:`fempipe.cli.parsing`."""
    group.add_argument("--allow-large", action="store_true", help=help)


def add_integration_arguments(
    parser, *, shoot_rtol: str, shoot_help: str, group=None, per: str = "in tau"
):
    """``--t-max``, ``--rtol``, ``--shoot-rtol`` in ``group`` (default a new one), returned."""
    g = group if group is not None else parser.add_argument_group("time integration")
    g.add_argument(
        "--t-max",
        metavar="T",
        type=parsing.number_type("--t-max", 0.0, strict_low=True),
        default="300",
        help=f"longest integration {per} (300; above {parsing.T_MAX:g} needs --allow-large)",
    )
    number(
        g, "--rtol", "TOL", "1e-5", "tolerance of the transient (1e-5)", 0.0, 0.1, strict_low=True
    )
    add_shoot_rtol_argument(g, shoot_help, shoot_rtol)
    return g


def add_shoot_rtol_argument(group, help: str, default: str = "1e-9") -> None:
    """``--shoot-rtol TOL``: the integration tolerance of a limit cycle's shooting."""
    number(group, "--shoot-rtol", "TOL", default, f"{help} ({default})", 0.0, 0.1, strict_low=True)


def add_workers_argument(group, help: str, default: str | None = "1") -> None:
    """``--workers N``, a positive integer."""
    group.add_argument(
        "--workers", metavar="N", type=parsing.workers_type, default=default, help=help
    )


def add_planar_argument(group, what: str) -> None:
    """``--planar``: the paper's planar model alone; ``what`` says what changes."""
    group.add_argument(
        "--planar",
        action="store_true",
        help="the paper's planar model only: no analysis of the motion out of the plane "
        f"({what}, every output as before)",
    )


def add_error_estimate_argument(parser: argparse.ArgumentParser, what: str) -> None:
    """``--error-estimate``; ``what`` names the numbers it covers."""
    parser.add_argument_group("error estimate").add_argument(
        "--error-estimate",
        action="store_true",
        help=f"also run on the refined discretization (FE: every element halved; modal: twice "
        f"the modes) and report beside {what} its error estimate KEY_error = "
        "max(3 abs(Q - Q_refined) 2^p / (2^p - 1), solver tolerance) (Roache's Grid Convergence "
        "Index; p = 2k for Pk, 3 for sine modes, 4 for beam modes) and KEY_refined; costs about "
        "the refined run",
    )


def add_output_arguments(parser: argparse.ArgumentParser, out_help: str | None = None) -> None:
    """``--json``, ``--out DIR`` and ``--progress`` / ``--quiet``."""
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
# From the parsed options to the validated problem
# ---------------------------------------------------------------------------

#: SI option -> PipeSI field.
SI_OPTIONS = {"--length": "L", "--EI": "EI", "--m": "m", "--M": "M", "--g": "g", "--a": "a"}
_SI_REQUIRED = ("--length", "--EI", "--m", "--M")
#: Params / PipeSI field -> the option that sets it.
_OPTION = {f: o for o, f in SI_OPTIONS.items()} | {
    "alpha": "--alpha",
    "beta": "--beta",
    "gamma": "--length --EI --m --M --g",
    "mu": "--a",
    "end_mass": "--end-mass",
    "external_damping": "--external-damping",
    "hysteretic_damping": "--hysteretic-damping",
    "springs": "--spring",
}


@dataclass(frozen=True)
class Setup:
    """The validated problem behind a command line: ``params.v`` is the first of the flow
    velocities ``v`` (0 if none); ``pipe`` and ``U`` (m/s) with an SI pipe, else None."""

    params: Params
    pipe: PipeSI | None
    v: list[float]
    disc: object
    U: list[float] | None = None

    def to_dict(self) -> dict:
        """``params`` (with ``pipe_SI`` and its scales when SI) and ``discretization``."""
        p = self.params.to_dict()
        p.pop("v", None)
        if self.pipe is not None:
            p["pipe_SI"] = self.pipe.to_dict()
            p["time_scale_s"] = self.pipe.time_scale
            p["velocity_scale_m_per_s"] = self.pipe.velocity_scale
        return {"params": p, "discretization": self.disc.to_dict()}


def flow_option(args: argparse.Namespace) -> str:
    """The flow option given: ``--U`` or ``--v`` (to name it in messages)."""
    return "--U" if getattr(args, "U", None) is not None else "--v"


def setup_from_args(args: argparse.Namespace, need_flow: bool = True) -> Setup:
    """The validated :class:`Setup` of parsed options; CLIError naming the offending option.

    ``need_flow=False`` allows a missing flow list even without a default.
    """
    a = vars(args)
    large = parsing.allow_large(args)
    pipe, base = _pipe(a)
    base = _with_variants(a, base, pipe)
    v, U = _flows(a, pipe, large, need_flow)
    if pipe is not None and a.get("a") is None:
        # The two ways of giving the pipe differ in one default; fempipe.cli.main prints it.
        args.__dict__.setdefault("_notices", []).append(
            "the SI pipe has no Kelvin-Voigt damping unless --a is given "
            f"(mu = 0 here; a dimensionless run takes the paper's mu = {DEFAULT_MU:g})"
        )
    params = replace(base, v=v[0]) if v else base
    return Setup(params=params, pipe=pipe, v=v, disc=_discretization(a, large), U=U)


def _pipe(a: dict) -> tuple[PipeSI | None, Params]:
    """``(pipe, params at v = 0)``: the SI pipe, or the dimensionless groups (pipe None)."""
    alpha = a.get("alpha") or 0.0
    si_given = [opt for opt in SI_OPTIONS if a.get(opt[2:]) is not None]
    try:
        if not si_given:
            groups = {"beta": DEFAULT_BETA, "gamma": DEFAULT_GAMMA, "mu": DEFAULT_MU}
            groups |= {k: a.get(k) for k in groups if a.get(k) is not None}
            return None, Params(alpha=alpha, **groups)
        missing = [opt for opt in _SI_REQUIRED if a.get(opt[2:]) is None]
        if missing:
            # Blame the option that asked for the SI pipe when none of the required ones
            # was given (--g 9.8 alone), else the first missing one.
            named = missing[0] if len(missing) < len(_SI_REQUIRED) else si_given[0]
            needs = " ".join(_SI_REQUIRED)
            raise CLIError(
                named, f"the SI pipe needs {needs} together; missing {' '.join(missing)}"
            )
        for opt in ("--beta", "--gamma", "--mu"):
            if a.get(opt[2:]) is not None:
                raise CLIError(
                    opt,
                    f"cannot be combined with the SI pipe ({si_given[0]}): "
                    "beta, gamma, mu follow from --length --EI --m --M --g --a",
                )
        kw = {f: a.get(o[2:]) for o, f in SI_OPTIONS.items()}
        kw = {f: x for f, x in kw.items() if x is not None}
        pipe = PipeSI(alpha=alpha, **({"g": DEFAULT_G} | kw))
        return pipe, ranges.check_pipe(pipe.params(0.0))
    except ParamError as exc:
        option = _OPTION.get(exc.field, "--" + exc.field) if si_given else "--" + exc.field
        raise CLIError(option, str(exc)) from None


def _flows(a: dict, pipe: PipeSI | None, large: bool, need_flow: bool):
    """``(v, U)``: the flow velocities, dimensionless and in m/s (None without an SI pipe)."""
    if a.get("U") is not None:
        if pipe is None:
            raise CLIError(
                "--U", "needs the SI pipe (--length --EI --m --M); use --v for dimensionless flow"
            )
        parsing.check_U(pipe, a.get("U"))
        U = a.get("U").values(large)
        return [pipe.v_of_U(x) for x in U], U
    spec = a.get("v")
    if spec is None and a.get("_flow_default") is not None:
        spec = parsing.v_list_type(a["_flow_default"])
    if spec is None and need_flow and "_flow_default" in a:
        raise CLIError("--v", "give the flow velocities (--v or --U)")
    v = [] if spec is None else spec.values(large)
    return v, ([pipe.U_of_v(x) for x in v] if pipe is not None and v else None)


def _discretization(a: dict, large: bool):
    """``--fe`` or ``--modal`` (with ``--basis``), within the unknowns' work limit."""
    from fempipe.model.discretization import parse_discretization

    fe, modal, basis = a.get("fe"), a.get("modal"), a.get("basis") or "sine"
    if basis != "sine" and modal is None:
        raise CLIError(
            "--basis",
            f"{basis} chooses the modes of --modal N and needs it"
            + (" (finite elements --fe have no basis)" if fe is not None else ""),
        )
    option, (_, unknowns) = ("--modal", modal) if modal is not None else ("--fe", fe or (None, 0))
    parsing.check_count(option, unknowns, parsing.MAX_DOFS, large, "unknowns")
    try:
        return parse_discretization(
            fe=None if fe is None else fe[0], modal=None if modal is None else modal[0], basis=basis
        )
    except ValueError as exc:
        raise CLIError(option, str(exc)) from None


def _with_variants(a: dict, base: Params, pipe: PipeSI | None) -> Params:
    """``base`` with the end mass, dampings and springs of the command line."""
    end_mass, kg = a.get("end_mass"), a.get("end_mass_kg")
    if kg is not None:
        if pipe is None:
            raise CLIError(
                "--end-mass-kg",
                "needs the SI pipe (--length --EI --m --M); use "
                "--end-mass for the dimensionless Gamma = M_e / ((m+M) L)",
            )
        if end_mass is not None:
            raise CLIError("--end-mass-kg", "give --end-mass or --end-mass-kg, not both")
        end_mass = pipe.end_mass_ratio(kg)
        if end_mass > parsing.END_MASS_MAX:
            raise CLIError(
                "--end-mass-kg",
                f"M_e = {kg:g} kg is Gamma = {end_mass:.6g} > {parsing.END_MASS_MAX:g} times "
                "the pipe's mass",
            )
    kw = {
        "end_mass": end_mass,
        "external_damping": a.get("external_damping"),
        "hysteretic_damping": a.get("hysteretic_damping"),
        "springs": tuple(a.get("spring") or ()) or None,
    }
    kw = {k: x for k, x in kw.items() if x is not None}
    try:
        return replace(base, **kw) if kw else base
    except ParamError as exc:
        raise CLIError(_OPTION.get(exc.field, "--" + exc.field), str(exc)) from None


def refuse_hysteretic(args: argparse.Namespace, command: str) -> None:
    """Time-domain commands: hysteretic damping has no meaning there (CLIError)."""
    if getattr(args, "hysteretic_damping", None):
        raise CLIError(
            "--hysteretic-damping",
            "has no time-domain meaning (EI (1 + i mu_h) acts on harmonic motion only); "
            f"{command} cannot use it: use spectrum, critical or stability-map",
        )
