"""``fempipe spectrum``: eigenvalues of the linearized problem, Eq. (32), against the flow velocity.

Mode numbers carried by continuity from v = 0 (:func:`fempipe.analyses.stability.trace_root_locus`),
in and out of the plane (``stable``: the verdict in three dimensions) or with ``--planar`` in the
plane only.  Keys and files: docs/cli/commands.md, "fempipe spectrum".
"""

from __future__ import annotations

import argparse
import math

from fempipe.cli import common, parsing, reporting
from fempipe.cli.parsing import CLIError

EXAMPLES = (
    "fempipe spectrum --alpha pi --v 0:6:61 --out out-spectrum/   # Argand diagram like Fig. 5",
    "fempipe spectrum --alpha pi/2 --modal 4 --v 6 --json",
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    common.add_problem_arguments(parser, "0:10:51")
    g = parser.add_argument_group("spectrum")
    g.add_argument(
        "--modes",
        metavar="N",
        type=parsing.option_type("--modes", _modes),
        default="4",
        help="report modes 1..N (default 4) and every unstable one; 'all' for every resolved mode",
    )
    common.add_planar_argument(g, "stable is then the verdict in the plane")
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
    from fempipe.analyses.stability import PLANES, trace_root_locus
    from fempipe.model.plane.operators import PipeModel

    setup = common.setup_from_args(args)
    n_modes = args.modes
    values = list(setup.v)
    if not values:
        raise CLIError("--v", "no flow velocities given")
    model = PipeModel(setup.disc, setup.params)
    with reporting.progress(args, len(values), "spectrum") as bar:
        try:
            loci = trace_root_locus(
                model,
                values,
                planes=("in",) if args.planar else PLANES,
                n_modes=n_modes,
                callback=lambda i, v: bar.update(),
            )
            locus, out_locus = (loci, None) if args.planar else loci
        except ValueError as exc:
            raise CLIError("--fe" if args.modal is None else "--modal", str(exc)) from None
    result = locus.to_dict() | setup.to_dict() | {"n_spectra": locus.n_spectra}
    if out_locus is not None:
        result = _with_out_of_plane(result, locus, out_locus)
    if setup.pipe is not None:
        for pt in result["points"]:
            pt["U"] = setup.pipe.U_of_v(pt["v"])
    reporting.deliver(
        args,
        result,
        write=lambda output: _write(output, result, locus, out_locus),
        text=lambda: _print_table(result, locus, out_locus),
    )
    return 0


def _with_out_of_plane(result: dict, locus, out_locus) -> dict:
    """The planar result with the out-of-plane spectrum and the verdict in three dimensions."""
    points = []
    for pt, po in zip(result["points"], out_locus.to_dict()["points"], strict=True):
        points.append(
            {"v": pt["v"], "stable": pt["stable"] and po["stable"]}
            | {"max_real": max(pt["max_real"], po["max_real"]), "theta_tip": pt["theta_tip"]}
            | {"eigenvalues": [dict(e, plane="in") for e in pt["eigenvalues"]]}
            | {"stable_in_plane": pt["stable"], "stable_out_of_plane": po["stable"]}
            | {"max_real_in_plane": pt["max_real"], "max_real_out_of_plane": po["max_real"]}
            | {"eigenvalues_out_of_plane": [dict(e, plane="out") for e in po["eigenvalues"]]}
        )
    return {
        "params": result["params"],
        "modes": result["modes"],
        "points": points,
        "modes_out_of_plane": out_locus.modes.tolist(),
        "discretization": result["discretization"],
        "n_spectra": locus.n_spectra + out_locus.n_spectra,
        "n_spectra_in_plane": locus.n_spectra,
        "n_spectra_out_of_plane": out_locus.n_spectra,
    }


def _rows(result: dict, key: str = "eigenvalues") -> list[dict]:
    """One CSV row per v and eigenvalue of ``pt[key]``, with the point's ``stable``."""
    rows = []
    for pt in result["points"]:
        members: dict = {}
        for i, e in enumerate(pt[key]):
            members[e["mode"]] = members.get(e["mode"], 0) + 1
            row = {
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
            if key != "eigenvalues":
                row["plane"] = e["plane"]
            rows.append(row)
    return rows


def _write(output: reporting.Output, result: dict, locus, out_locus) -> None:
    reporting.agg()
    from fempipe.plotting.stability import plot_argand

    ax = plot_argand(locus, out_of_plane=out_locus)
    output.json("spectrum.json", result)
    output.csv("spectrum.csv", _rows(result))
    if out_locus is not None:
        output.csv("spectrum_out_of_plane.csv", _rows(result, "eigenvalues_out_of_plane"))
    output.figure("argand.png", ax.figure)


def _print_table(result: dict, locus, out_locus) -> None:
    disc, head = reporting.describe(result)
    print(f"spectrum (Omega = -i lambda; Im Omega < 0 unstable), {head}; discretization {disc}")
    if out_locus is None:
        _table(result, locus, "eigenvalues", "stable", "max_real")
        return
    print(
        "in the plane of the static state (Eq. (32)); 'stable' is the verdict in three "
        "dimensions, 'in' and 'out' each plane's, 'max Re lam' both planes'"
    )
    _table(result, locus, "eigenvalues", "stable", "max_real", planes=True)
    print("out of the plane (docs, 'Out of the plane'):")
    _table(
        result,
        out_locus,
        "eigenvalues_out_of_plane",
        "stable_out_of_plane",
        "max_real_out_of_plane",
    )


def _table(result: dict, locus, key: str, stable: str, max_real: str, planes: bool = False) -> None:
    """One row per v: the verdict, the largest Re lambda and the modes' Omega."""
    # The first four modes and every unstable one (the table has one column each).
    unstable = {e["mode"] for pt in result["points"] for e in pt[key] if e["re"] > 0}
    labels = sorted({int(m) for m in locus.modes})
    modes = sorted(set(labels[:4]) | {m for m in labels if m in unstable})
    cols = "".join(f"   mode {m}: Re Omega  Im Omega" for m in modes)
    verdicts = f" {'in':>5} {'out':>5}" if planes else ""
    print(f"{'v':>8} {'stable':>6}{verdicts} {'max Re lam':>11}{cols}")
    for pt in result["points"]:
        cells = []
        for m in modes:
            # The member with Re Omega >= 0 (or the rightmost real root).
            es = [e for e in pt[key] if e["mode"] == m]
            if not es:
                cells.append(" " * 29)
                continue
            e = max(es, key=lambda e: (e["Omega_re"] >= 0, -e["Omega_im"]))
            cells.append(f"   {e['Omega_re']:>13.6f} {e['Omega_im']:>+11.6f}")
        mr = pt[max_real]
        mr_s = f"{mr:+11.3e}" if math.isfinite(mr) else f"{'-':>11}"
        flags = (
            f" {str(pt['stable_in_plane']):>5} {str(pt['stable_out_of_plane']):>5}"
            if planes
            else ""
        )
        print(f"{pt['v']:8.4f} {str(pt[stable]):>6}{flags} {mr_s}" + "".join(cells))
