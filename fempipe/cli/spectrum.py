"""``fempipe spectrum``: eigenvalues of the linearised problem against the flow velocity.

Follows the static branch (gravity loading, then the flow values of ``--v`` or
``--U`` in order) and computes the resolved eigenvalues of Eq. (32) at every
value (:func:`fempipe.stability.root_locus`).  Mode numbers are intrinsic:
carried by continuity from the modes at v = 0, whatever the range start or
the mesh; modes 1..``--modes`` are reported, and every mode that is unstable
at some v whatever its number.  Both conventions are given: lambda
(theta^d ∝ e^{lambda tau}, Re lambda > 0 unstable) and the paper's
Omega = -i lambda (Im Omega < 0 unstable).

``--json`` prints ``{"points": [{"v", "stable", "max_real", "theta_tip",
"eigenvalues": [{"mode", "re", "im", "Omega_re", "Omega_im"}, ...]}, ...],
"modes", "params", "discretization"}``.  ``--out DIR`` writes spectrum.json,
spectrum.csv (one row per v and eigenvalue) and argand.png (Re Omega against
Im Omega with v marked along the loci, like Fig. 5).
"""

from __future__ import annotations

import argparse
import math

from fempipe.cli import common, parsing, reporting
from fempipe.cli.parsing import CLIError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    common.add_physical_arguments(parser)
    common.add_flow_arguments(parser, default="0:10:51")
    common.add_discretization_arguments(parser)
    g = parser.add_argument_group("spectrum")
    g.add_argument(
        "--modes",
        metavar="N",
        type=parsing.option_type("--modes", _modes),
        default="4",
        help="report modes 1..N (default 4) and every unstable one; 'all' for every resolved mode",
    )
    common.add_output_arguments(parser)


def _modes(text: str) -> int | None:
    """``--modes``: a number of modes >= 1, or None for 'all'."""
    if str(text).strip().lower() == "all":
        return None
    try:
        n = int(text)
    except ValueError:
        raise ValueError(f"expects an integer >= 1 or 'all', got {text!r}") from None
    if n < 1:
        raise ValueError(f"expects an integer >= 1 or 'all', got {n}")
    return n


def run(args: argparse.Namespace) -> int:
    from fempipe.io import json_dumps
    from fempipe.operators import PipeModel
    from fempipe.stability import root_locus

    setup = common.setup_from_args(args)
    n_modes = args.modes
    values = list(setup.v)
    if not values:
        raise CLIError("--v", "no flow velocities given")
    model = PipeModel(setup.disc, setup.params)
    with reporting.progress(args, len(values), "spectrum") as bar:
        try:
            locus = root_locus(model, values, n_modes=n_modes, callback=lambda i, v: bar.update())
        except ValueError as exc:
            raise CLIError("--fe" if args.modal is None else "--modal", str(exc)) from None
    head = setup.to_dict()
    result = locus.to_dict()
    result["params"] = head["params"]
    result["discretization"] = head["discretization"]
    result["n_spectra"] = locus.n_spectra
    if setup.pipe is not None:
        for pt in result["points"]:
            pt["U"] = setup.pipe.U_of_v(pt["v"])
    output = reporting.Output(args.out) if args.out is not None else None
    if output is not None:
        _write(output, result, locus)
    if args.json:
        print(json_dumps(result))
    else:
        _print_table(result, locus)
    if output is not None:
        output.report(args)
    return 0


def _rows(result: dict) -> list[dict]:
    rows = []
    for pt in result["points"]:
        members: dict = {}
        for i, e in enumerate(pt["eigenvalues"]):
            members[e["mode"]] = members.get(e["mode"], 0) + 1
            rows.append(
                {
                    "v": pt["v"],
                    "mode": e["mode"],
                    "lambda_re": e["re"],
                    "lambda_im": e["im"],
                    "Omega_re": e["Omega_re"],
                    "Omega_im": e["Omega_im"],
                    "stable": pt["stable"],
                    "eigenvalue_index": i,
                    "pair_member": members[e["mode"]],
                    "system_stable": pt["stable"],
                }
            )
    return rows


def _write(output: reporting.Output, result: dict, locus) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fempipe.plotting.stability import plot_argand

    ax = plot_argand(locus)
    try:
        output.json("spectrum.json", result)
        output.csv("spectrum.csv", _rows(result))
        output.figure("argand.png", ax.figure, dpi=150)
    finally:
        plt.close(ax.figure)


def _print_table(result: dict, locus) -> None:
    disc, head = reporting.describe(result)
    print(f"spectrum (Omega = -i lambda; Im Omega < 0 unstable), {head}; discretisation {disc}")
    # The first four modes and every unstable one (the table has one column each).
    unstable = {e["mode"] for pt in result["points"] for e in pt["eigenvalues"] if e["re"] > 0}
    labels = sorted({int(m) for m in locus.modes})
    modes = sorted(set(labels[:4]) | {m for m in labels if m in unstable})
    cols = "".join(f"   mode {m}: Re Omega  Im Omega" for m in modes)
    print(f"{'v':>8} {'stable':>6} {'max Re lam':>11}{cols}")
    for pt in result["points"]:
        cells = []
        for m in modes:
            # The member with Re Omega >= 0 (or the rightmost real root).
            es = [e for e in pt["eigenvalues"] if e["mode"] == m]
            if not es:
                cells.append(" " * 29)
                continue
            e = max(es, key=lambda e: (e["Omega_re"] >= 0, -e["Omega_im"]))
            cells.append(f"   {e['Omega_re']:>13.6f} {e['Omega_im']:>+11.6f}")
        mr = pt["max_real"]
        mr_s = f"{mr:+11.3e}" if math.isfinite(mr) else f"{'-':>11}"
        print(f"{pt['v']:8.4f} {str(pt['stable']):>6} {mr_s}" + "".join(cells))
