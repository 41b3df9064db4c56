"""The one option parser shared by every ``fempipe`` subcommand.

Every subcommand that solves the pipe takes the same physical parameters,
discretization, flow values and output options; they are declared here once
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
    U_list_type,
    alpha_type,
    beta_type,
    fe_type,
    gamma_type,
    modal_type,
    mu_type,
    number_type,
    spring_type,
    v_list_type,
    workers_type,
)
from .setup import Setup, refuse_hysteretic, setup_from_args

__all__ = [
    "ArgumentParser",
    "Setup",
    "add_discretization_arguments",
    "add_flow_arguments",
    "add_output_arguments",
    "add_physical_arguments",
    "refuse_hysteretic",
    "setup_from_args",
]


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

    g = parser.add_argument_group("discretization and work limits")
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
