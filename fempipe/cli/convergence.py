"""``fempipe convergence``: a convergence study of one quantity of the user's case.

FE meshes of doubling element counts and doubling numbers of modes against the Richardson
extrapolated reference, each family's observed order (:func:`fempipe.studies.convergence.run_study`);
static tip values also by collocation.  Keys and files: docs/cli/commands.md, "fempipe convergence".
"""

from __future__ import annotations

import argparse
import math

from fempipe.cli import common, parsing, reporting
from fempipe.cli.parsing import CLIError

EXAMPLES = (
    "fempipe convergence --quantity v_cr --alpha pi/2 --v 0,10 --fe P1,P2,P3 --modal 2:32 "
    "--basis sine,beam --out out-conv/",
    "fempipe convergence --quantity lc_amplitude --alpha 0 --v 10 --elements 2:32 --modal 2:16 "
    "--workers 2",
)

DEFAULT_DEGREES = "P1,P2,P3"
DEFAULT_ELEMENTS = "2:64"
DEFAULT_MODES = "2:32"


def _degrees(text: str) -> list[int]:
    """``--fe P1,P2,P3``: distinct element degrees."""
    out = []
    for item in str(text).split(","):
        item = item.strip()
        if not (item[:1] in "Pp" and item[1:].isdigit() and 1 <= int(item[1:]) <= 10):
            raise ValueError(f"expects element degrees P1..P10 separated by commas, got {item!r}")
        out.append(int(item[1:]))
    if len(set(out)) != len(out):
        raise ValueError(f"lists a degree twice: {text!r}")
    return out


def _sizes(text: str) -> list[int]:
    """``LOW:HIGH`` (doubling from LOW up to HIGH) or ``a,b,c`` (increasing)."""
    from fempipe.studies.convergence import doubling

    text = str(text).strip()
    try:
        if ":" in text:
            lo, hi = (int(x) for x in text.split(":"))
            if lo < 1 or hi < 2 * lo:
                raise ValueError
            return doubling(lo, hi)
        sizes = [int(x) for x in text.split(",")]
    except ValueError:
        raise ValueError(
            f"expects LOW:HIGH with 1 <= LOW and HIGH >= 2 LOW (sizes doubling from LOW), "
            f"or an increasing list a,b,c of at least two sizes, got {text!r}"
        ) from None
    if (
        len(sizes) < 2
        or sizes[0] < 1
        or any(b <= a for a, b in zip(sizes[:-1], sizes[1:], strict=True))
    ):
        raise ValueError(f"expects an increasing list of at least two sizes >= 1, got {text!r}")
    return sizes


def _bases(text: str) -> list[str]:
    """``--basis sine,beam``."""
    out = [b.strip() for b in str(text).split(",")]
    bad = [b for b in out if b not in ("sine", "beam")]
    if bad or len(set(out)) != len(out):
        raise ValueError(f"expects sine, beam or sine,beam, got {text!r}")
    return out


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from fempipe.studies.convergence import QUANTITIES

    common.add_physical_arguments(parser)
    common.add_flow_arguments(parser, default=None)
    g = parser.add_argument_group("the study")
    g.add_argument(
        "--quantity",
        required=True,
        choices=list(QUANTITIES),
        help="static tip values at one v (theta_tip, X_tip, Z_tip, eta_tip); v_cr and the "
        "frequency of the critical event over the --v range (in three dimensions; "
        "v_cr_in_plane, frequency_in_plane: in the plane of the static state, the paper's; "
        "v_cr_out_of_plane, frequency_out_of_plane: out of it); eigenvalue: the --mode-th "
        "eigenvalue at one v; lc_amplitude, lc_period: the limit cycle at one v; "
        "sigma_threshold, omega_threshold: where the pipe first resonates under a "
        "pulsating flow about the mean flow --v, in the --omega band",
    )
    common.option(
        g, "--mode", "K", parsing.positive_int, "1", "mode number of --quantity eigenvalue (1)"
    )
    g.add_argument(
        "--omega",
        metavar="A:B",
        type=parsing.option_type("--omega", parsing.parse_band),
        default=None,
        help="the pulsation frequencies searched by --quantity sigma_threshold, omega_threshold "
        "(the first region of parametric resonance to open), e.g. 20:40",
    )
    g.add_argument(
        "--sigma-max",
        metavar="S",
        type=parsing.number_type("--sigma-max", 0.0, 1.0, strict_low=True),
        default=0.5,
        help="the largest pulsation amplitude they search (0.5)",
    )
    g.add_argument(
        "--fe",
        dest="fe_degrees",
        metavar="LIST",
        type=parsing.option_type("--fe", _degrees),
        default=None,
        help=f"element degrees, e.g. {DEFAULT_DEGREES} (default {DEFAULT_DEGREES} when "
        "--modal is not given)",
    )
    g.add_argument(
        "--elements",
        metavar="LOW:HIGH",
        type=parsing.option_type("--elements", _sizes),
        default=DEFAULT_ELEMENTS,
        help=f"element counts, doubling from LOW to HIGH, or a list a,b,c ({DEFAULT_ELEMENTS})",
    )
    g.add_argument(
        "--modal",
        dest="modal_sizes",
        metavar="LOW:HIGH",
        type=parsing.option_type("--modal", _sizes),
        default=None,
        help=f"numbers of modes, doubling from LOW to HIGH, or a list (default {DEFAULT_MODES} "
        "when --fe is not given)",
    )
    g.add_argument(
        "--basis",
        dest="bases",
        metavar="LIST",
        type=parsing.option_type("--basis", _bases),
        default="sine",
        help="modal bases: sine (the paper's sin((2r-1) pi xi/2)), beam (slopes of the "
        "clamped-free beam modes), or sine,beam (default sine)",
    )
    common.add_shoot_rtol_argument(
        g, "integration tolerance of the limit cycle's shooting (lc_* quantities)"
    )
    common.add_workers_argument(g, "processes computing members in parallel (1)")
    common.add_allow_large_argument(g, f"accept members with more than {parsing.MAX_DOFS} unknowns")
    common.add_output_arguments(parser)


def _families(args: argparse.Namespace) -> list:
    from fempipe.studies.convergence import Family

    degrees, modes = args.fe_degrees, args.modal_sizes
    if degrees is None and modes is None:
        degrees, modes = _degrees(DEFAULT_DEGREES), _sizes(DEFAULT_MODES)
    fams = []
    for k in degrees or []:
        sizes = tuple(args.elements)
        parsing.check_count(
            "--elements",
            k * sizes[-1],
            parsing.MAX_DOFS,
            args.allow_large,
            f"unknowns (P{k}:{sizes[-1]})",
        )
        fams.append(Family("fe", sizes, degree=k))
    if modes is not None:
        parsing.check_count("--modal", modes[-1], parsing.MAX_DOFS, args.allow_large, "unknowns")
        for b in args.bases:
            fams.append(Family("modal", tuple(modes), basis=b))
    elif "beam" in args.bases:
        raise CLIError("--basis", "applies to --modal; give --modal LOW:HIGH as well")
    return fams


def _quantity(args: argparse.Namespace, setup):
    from dataclasses import replace

    from fempipe.studies.convergence import (
        CRITICAL_QUANTITIES,
        CYCLE_QUANTITIES,
        PARAMETRIC_QUANTITIES,
        Quantity,
    )

    name = args.quantity
    flow_opt = common.flow_option(args)
    if name in CYCLE_QUANTITIES:
        common.refuse_hysteretic(args, f"--quantity {name} (a limit cycle)")
    if name in CRITICAL_QUANTITIES:
        if len(setup.v) < 2 or max(setup.v) <= min(setup.v):
            raise CLIError(flow_opt, f"--quantity {name} needs a flow range, e.g. --v 0,15")
        params = replace(setup.params, v=min(setup.v))
        return Quantity(name, params, v_max=max(setup.v), shoot_rtol=args.shoot_rtol)
    if len(setup.v) != 1:
        got = "none" if not setup.v else f"{len(setup.v)} values"
        raise CLIError(
            flow_opt, f"--quantity {name} needs one flow velocity, e.g. --v 3; got {got}"
        )
    if name in PARAMETRIC_QUANTITIES:
        if args.omega is None:
            raise CLIError("--omega", f"--quantity {name} needs the band searched, e.g. 20:40")
        try:
            return Quantity(name, setup.params, omega_band=args.omega, sigma_max=args.sigma_max)
        except ValueError as exc:
            raise CLIError("--quantity", str(exc)) from None
    return Quantity(name, setup.params, mode=args.mode, shoot_rtol=args.shoot_rtol)


def run(args: argparse.Namespace) -> int:
    import time

    from fempipe.model.discretization import FiniteElement
    from fempipe.studies.convergence import CYCLE_QUANTITIES, STATIC_QUANTITIES, run_study

    setup = common.setup_from_args(args, need_flow=False)
    quantity = _quantity(args, setup)
    families = _families(args)
    t0 = time.process_time()
    independent = []
    total = sum(len(f.sizes) for f in families)
    with reporting.progress(args, total + 1, f"convergence {quantity.name}") as bar:
        if quantity.name in CYCLE_QUANTITIES:
            # One transient on the default mesh; every member shoots from it.
            bar.set_postfix_str("seed cycle P3:16")
            quantity = quantity.seeded(FiniteElement(16, 3))
        if quantity.name in STATIC_QUANTITIES:
            independent.append(_bvp_value(quantity))
        bar.update()

        def on_member(done: int, total: int) -> None:
            bar.update()
            bar.set_postfix_str(f"{done}/{total} members")

        study = run_study(
            quantity,
            families,
            workers=args.workers,
            callback=on_member,
            independent=[x for x in independent if x is not None],
        )
    result = study.to_dict()
    head = setup.to_dict()
    result["params"] = head["params"]
    result["cpu_time"] = reporting.cpu_seconds(t0)
    reporting.deliver(
        args, result, write=lambda out: _write(out, result, study), text=lambda: _print(result)
    )
    return 0


def _bvp_value(quantity) -> tuple[str, float] | None:
    """The static tip value by collocation of the strong form, Eq. (31a), on the FE branch."""
    from fempipe.core.errors import SolverError
    from fempipe.model.discretization import FiniteElement
    from fempipe.studies.convergence import static_tip_state
    from fempipe.validation.bvp import solve_static_bvp

    p = quantity.params
    disc = FiniteElement(32, 3)
    try:
        q = static_tip_state(disc, p)
    except SolverError:
        return None
    # The FE state selects the branch (there are several equilibria at large gamma).
    try:
        bvp = solve_static_bvp(
            p.alpha, p.gamma, p.v, guess=lambda x: disc.evaluate(q, x), tol=1e-11
        )
    except RuntimeError:
        return None  # the study stands without it; the output lists no collocation value
    method = f"solve_bvp (collocation of Eq. (31a), tolerance 1e-11, {bvp.n_nodes} nodes)"
    return method, float(getattr(bvp, quantity.name))  # theta_tip, X_tip, Z_tip or eta_tip


def _write(output: reporting.Output, result: dict, study) -> None:
    reporting.agg()
    from fempipe.plotting.convergence import plot_convergence

    name = result["quantity"]
    rows = []
    for s in study.series:
        for i, n in enumerate(s.n):
            row = {"family": s.family, "n": int(n), "dofs": int(s.dofs[i])}
            val = s.values[i]
            if name == "eigenvalue":
                row["eigenvalue_re"], row["eigenvalue_im"] = float(val.real), float(val.imag)
            else:
                row[name] = float(val)
            row[f"{name}_error"] = float(s.errors[i])
            rows.append(row)
    ax = plot_convergence(study)
    output.json("convergence.json", result)
    output.csv("convergence.csv", rows)
    output.figure("convergence.png", ax.figure)


def _fmt(x) -> str:
    if x is None:
        return "failed"
    if isinstance(x, list):
        return f"{x[0]:.12g}{x[1]:+.12g}i"
    return f"{x:.12g}"


def _print(result: dict) -> None:
    q = result["quantity_details"]
    p = result["params"]
    ref = result["reference"]
    print(
        f"convergence of {q['description']}; alpha = {p['alpha']:.6g}, beta = {p['beta']:g}, "
        f"gamma = {p['gamma']:g}, mu = {p['mu']:g}"
    )
    print(f"reference: {_fmt(ref['value'])} +- {ref['error_estimate']:.2e}")
    print(f"  formed by {ref['method']}")
    for d in ref["independent"]:
        print(
            f"  independent: {d['method']}: {_fmt(d['value'])} (differs by {d['difference']:.2e})"
        )
    print(f"{'family':>11} {'n':>5} {'dofs':>5} {'value':>26} {'|error|':>9}")
    for s in result["series"]:
        for n, d, v, e in zip(s["n"], s["dofs"], s["values"], s["errors"], strict=True):
            err = "-" if e is None or (isinstance(e, float) and math.isnan(e)) else f"{e:.2e}"
            print(f"{s['family']:>11} {n:>5} {d:>5} {_fmt(v):>26} {err:>9}")
    from fempipe.studies.convergence.study import ORDER_BAND

    for s in result["series"]:
        order = s["observed_order"]
        fit = ", ".join(str(n) for n in s["fit_points"]) or "none"
        exp = "unknown" if s["expected_order"] is None else f"{s['expected_order']:g}"
        got = "n/a" if order is None else f"{order:.3f}"
        note = ""
        if s["order_verdict"] in ("pre-asymptotic", "super-convergent"):
            lo, hi = s["expected_order"] - ORDER_BAND, s["expected_order"] + ORDER_BAND
            where = "below" if s["order_verdict"] == "pre-asymptotic" else "above"
            note = f": {s['order_verdict']}, {where} the theory's band [{lo:g}, {hi:g}]"
        print(f"{s['family']}: observed order {got} in dofs (fit on n = {fit}); theory {exp}{note}")
        for n, msg in s["failures"].items():
            print(f"  n = {n} failed: {msg}")
    print(f"CPU time {result['cpu_time']:.1f} s (this process and its workers)")
