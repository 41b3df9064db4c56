"""Command-line interface: ``fempipe <subcommand>``; one module per subcommand."""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Collection

# The BLAS thread variables are set by main() before numpy loads;
# fempipe.core.parallel imports only the standard library.  (Who set which
# variable: fempipe.core.parallel.BLAS_SET_BY_FEMPIPE, rebound by the call.)
from fempipe.core.parallel import BLAS_THREAD_VARIABLES, one_blas_thread

__all__ = ["SUBCOMMANDS", "BLAS_THREAD_VARIABLES", "build_parser", "main", "one_blas_thread"]

#: subcommand -> (module, one-line help).  Each module defines
#: ``add_arguments(parser)`` and ``run(args) -> int``, and optionally
#: ``solver_error_hint(args) -> str | None``, a sentence added to the message
#: of a solver failure (e.g. where finished work was kept).
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


def build_parser(only: Collection[str] | None = None) -> argparse.ArgumentParser:
    """The ``fempipe`` parser with one subparser per entry of :data:`SUBCOMMANDS`.

    Parameters
    ----------
    only : collection of str, optional
        Subcommands whose modules are imported and whose arguments are added;
        the others get a bare subparser (named, with their one-line help, in
        ``fempipe --help``).  None (the default): all of them.  :func:`main`
        passes the subcommand it runs, so that starting the command imports
        one subcommand module, not ten.
    """
    from fempipe.cli.common import ArgumentParser  # one-line errors, exit 2

    parser = ArgumentParser(
        prog="fempipe",
        description="Soft cantilevered pipe conveying fluid under gravity: "
        "finite elements and modal Galerkin (Chen et al. 2020, Eq. (20)).",
    )
    from fempipe.core.version import __version__

    parser.add_argument("--version", action="version", version=f"fempipe {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (module, help_) in SUBCOMMANDS.items():
        p = sub.add_parser(name, help=help_, description=help_)
        if only is not None and name not in only:
            continue
        mod = importlib.import_module(module)
        mod.add_arguments(p)
        p.set_defaults(_run=mod.run, _hint=getattr(mod, "solver_error_hint", None))
    return parser


def _subcommand(argv: list[str]) -> str | None:
    """The subcommand named in ``argv`` (the first known name), for error prefixes."""
    return next((a for a in argv if a in SUBCOMMANDS), None)


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit code.

    0 ok, 1 a solver failed (:class:`fempipe.core.errors.SolverError`), 2 bad input
    (:class:`~fempipe.cli.parsing.CLIError` or argparse, also an unusable
    ``--out``, checked before any computation), 130 / 143 interrupted by
    SIGINT / SIGTERM (workers stopped, one line on stderr, no traceback).
    Every error is one line ``fempipe COMMAND: error: --option: message``.
    A command that fails or is interrupted leaves its ``--out`` directory as
    it was (:class:`~fempipe.cli.reporting.Output`).
    """
    one_blas_thread()
    argv = list(sys.argv[1:] if argv is None else argv)
    command = _subcommand(argv)
    parser = build_parser(only=() if command is None else (command,))
    try:
        args, extra = parser.parse_known_args(argv)
        if args.command not in (None, command):  # pragma: no cover - argparse chose another
            parser = build_parser()
            args, extra = parser.parse_known_args(argv)
        if extra:
            # The top-level parser would say "fempipe: error: unrecognized
            # arguments: ..."; name the subcommand and the option like every
            # other message.
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
    from fempipe.core.errors import SolverError
    from fempipe.core.parallel import Interrupted, interruptible

    prefix = f"fempipe {args.command}: error:"

    def hint() -> str:
        text = args._hint(args) if args._hint is not None else None
        return f"; {text}" if text else ""

    try:
        if getattr(args, "out", None) is not None:
            check_out_dir(args.out)
        with interruptible():
            code = int(args._run(args) or 0)
        if getattr(args, "progress", None) is not False:  # --quiet: progress False
            for text in dict.fromkeys(getattr(args, "_notices", ())):
                print(f"fempipe {args.command}: notice: {text}", file=sys.stderr)
        return code
    except CLIError as exc:  # bad input: one line naming the option, exit 2
        print(f"{prefix} {exc}", file=sys.stderr)
        return 2
    except SolverError as exc:  # a solver failed: say where, exit 1
        print(f"{prefix} {' '.join(str(exc).split())}{hint()}", file=sys.stderr)
        return 1
    except Interrupted as exc:  # SIGINT or SIGTERM: workers are stopped by now
        print(f"fempipe {args.command}: {exc}{hint()}", file=sys.stderr)
        return exc.exit_code
    except OSError as exc:  # e.g. the disk filled up while writing: one line, no traceback
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"{prefix} {where}{exc.strerror or exc}", file=sys.stderr)
        return 1
    finally:
        discard_pending()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
