"""Command-line interface ``fempipe <subcommand>``, one module per subcommand (:data:`SUBCOMMANDS`).

Each module defines ``add_arguments(parser)``, ``run(args) -> int``, ``EXAMPLES`` and optionally
``solver_error_hint(args)``; only the command run is imported.  Exit codes: docs/cli/options.md.
"""

from __future__ import annotations

import argparse
import importlib
import re
import sys
from collections.abc import Collection

# The BLAS thread variables are set by main() before numpy loads.
from fempipe.core.parallel import BLAS_THREAD_VARIABLES, one_blas_thread

__all__ = ["SUBCOMMANDS", "BLAS_THREAD_VARIABLES", "build_parser", "main", "one_blas_thread"]

#: subcommand -> (module, one-line help).
SUBCOMMANDS: dict[str, tuple[str, str]] = {
    "static": ("fempipe.cli.static", "static large deformation against flow velocity"),
    "spectrum": ("fempipe.cli.spectrum", "eigenvalues of the linearized problem against v"),
    "critical": ("fempipe.cli.critical", "critical flow velocity and stability events"),
    "stability-map": ("fempipe.cli.stability_map", "v_cr against alpha for lists of beta, gamma"),
    "simulate": ("fempipe.cli.simulate", "nonlinear time integration and limit cycle"),
    "bifurcation": ("fempipe.cli.bifurcation", "bifurcation diagram of the tip response"),
    "convergence": (
        "fempipe.cli.convergence",
        "convergence study of one quantity: FE families and modal bases, observed orders",
    ),
    "compare": (
        "fempipe.cli.compare",
        "a user's results (CSV) against fempipe, with fempipe's error estimate",
    ),
    "parametric": (
        "fempipe.cli.parametric",
        "regions where a pulsating flow destabilizes the straight pipe (parametric resonance)",
    ),
    "validate": ("fempipe.cli.validate", "run the validation suite and write the report"),
    "bench": ("fempipe.cli.bench", "performance benchmarks"),
}


class ArgumentParser(argparse.ArgumentParser):
    """argparse with one-line errors ``prog: error: --option: message`` (exit 2)."""

    def error(self, message: str):  # noqa: D102 - argparse API
        message = re.sub(r"^argument (-[-\w]+)(?:/-[-\w]+)?: ", r"\1: ", " ".join(message.split()))
        self.exit(2, f"{self.prog}: error: {message}\n")

    def format_help(self) -> str:  # noqa: D102 - the epilogue's "::" is for the docs' RST
        return super().format_help().replace("examples::", "examples:")


def epilogue(name: str, examples: Collection[str]) -> str:
    """The end of ``fempipe NAME --help``: the examples and where the command is explained."""
    lines = "".join(f"  {e}\n" for e in examples)
    return (
        f"examples::\n\n{lines}\nwhat it computes, its --json keys and its files: "
        f'docs/cli/commands.md, "fempipe {name}"'
    )


def build_parser(only: Collection[str] | None = None) -> argparse.ArgumentParser:
    """The ``fempipe`` parser; only the subcommands in ``only`` (default all) get their
    arguments, the others a bare subparser named in ``fempipe --help``."""
    from fempipe.core.version import __version__

    parser = ArgumentParser(
        prog="fempipe",
        description="Soft cantilevered pipe conveying fluid under gravity: "
        "finite elements and modal Galerkin (Chen et al. 2020, Eq. (20)).",
    )
    parser.add_argument("--version", action="version", version=f"fempipe {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (module, help_) in SUBCOMMANDS.items():
        p = sub.add_parser(
            name,
            help=help_,
            description=help_,
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        if only is not None and name not in only:
            continue
        mod = importlib.import_module(module)
        mod.add_arguments(p)
        p.epilog = epilogue(name, getattr(mod, "EXAMPLES", ()))
        p.set_defaults(_run=mod.run, _hint=getattr(mod, "solver_error_hint", None))
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit code: 0 ok; 1 a solver or disk error; 2 bad input;
    130 / 143 SIGINT / SIGTERM (docs/cli/options.md)."""
    one_blas_thread()
    argv = list(sys.argv[1:] if argv is None else argv)
    command = next((a for a in argv if a in SUBCOMMANDS), None)
    parser = build_parser(only=() if command is None else (command,))
    try:
        args, extra = parser.parse_known_args(argv)
        if args.command not in (None, command):  # pragma: no cover - a value named a command
            parser = build_parser()
            args, extra = parser.parse_known_args(argv)
        if extra:  # named like every other message, not "fempipe: error: unrecognized ..."
            sub = f"fempipe {command}" if command else "fempipe"
            print(f"{sub}: error: {extra[0]}: unrecognized argument", file=sys.stderr)
            return 2
    except SystemExit as exc:  # argparse: --help, --version (0) or bad input (2)
        return 0 if exc.code is None else int(exc.code)
    if not getattr(args, "_run", None):
        parser.print_help(sys.stderr)
        return 2
    from fempipe.cli.parsing import CLIError
    from fempipe.cli.reporting import check_out_dir, discard_pending
    from fempipe.core.errors import PointStoreMismatchError, SolverError
    from fempipe.core.parallel import Interrupted, interruptible

    prefix = f"fempipe {args.command}:"
    hint = args._hint(args) if args._hint is not None else None
    hint = f"; {hint}" if hint else ""
    try:
        if getattr(args, "out", None) is not None:
            check_out_dir(args.out)
        with interruptible():
            code = int(args._run(args) or 0)
        if getattr(args, "progress", None) is not False:  # --quiet: progress False
            for text in dict.fromkeys(getattr(args, "_notices", ())):
                print(f"{prefix} notice: {text}", file=sys.stderr)
        return code
    except PointStoreMismatchError as exc:  # --out holds another run's points
        print(f"{prefix} error: {CLIError('--out', str(exc))}", file=sys.stderr)
        return 2
    except CLIError as exc:
        print(f"{prefix} error: {exc}", file=sys.stderr)
        return 2
    except SolverError as exc:
        print(f"{prefix} error: {' '.join(str(exc).split())}{hint}", file=sys.stderr)
        return 1
    except Interrupted as exc:  # SIGINT or SIGTERM: workers are stopped by now
        print(f"{prefix} {exc}{hint}", file=sys.stderr)
        return exc.exit_code
    except OSError as exc:  # e.g. a full disk: one line, no traceback
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"{prefix} error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 1
    finally:
        discard_pending()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
