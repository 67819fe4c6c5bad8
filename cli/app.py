"""The ``flightid`` command line: the commands of every group wired into one typer app,
and the one error policy of the command line (docs/errors.md).

The command bodies live in one module per command group (``flightid.cli.trim_truth``,
``simulate``, ``bridge``, ``frequency_response``, ``compatibility``); ``identify`` and
``demo`` still call the ``run_cli`` of their library modules.

Exit codes: 0 success; 1 internal error (a bug: one line naming the exception); 2 bad input
or usage (a missing or unreadable file, a bad option, a malformed card, an output that
cannot be written); 3 physical failure (the aircraft cannot be trimmed, the flight
departed, a bridge link never delivered). ``--debug`` (or ``FLIGHTID_DEBUG=1``) re-raises
with the full traceback; without it no traceback is ever printed.
"""

from __future__ import annotations

import os
import sys
from types import TracebackType

import numpy as np
import typer
from typer.core import TyperGroup
from typer.exceptions import TyperException

from flightid import __version__
from flightid.cli import bridge
from flightid.cli.compatibility import compatibility_command
from flightid.cli.demo import demo_command
from flightid.cli.design_compare import design_compare_command
from flightid.cli.design_optimize import design_optimize_command
from flightid.cli.effects import effects_command
from flightid.cli.frequency_response import frequency_response_command
from flightid.cli.gap import gap_command
from flightid.cli.gap_benchmark import gap_benchmark_command
from flightid.cli.identify import identify_command
from flightid.cli.importing import import_command
from flightid.cli.methods import methods_command
from flightid.cli.montecarlo import montecarlo_command, montecarlo_report_command
from flightid.cli.simulate import simulate_command
from flightid.cli.study_compare import study_compare_command
from flightid.cli.trim_truth import trim_command, truth_command
from flightid.identification.convergence import NotConvergedError
from flightid.scenarios.cards import CardError
from flightid.sim.flight import DepartureError
from flightid.sim.trim import TrimError, TrimInputError

EXIT_OK, EXIT_INTERNAL, EXIT_BAD_INPUT, EXIT_PHYSICAL = 0, 1, 2, 3
EXIT_NOT_CONVERGED = 4  # --strict and an iterative fit that did not converge
DEBUG_ENV = "FLIGHTID_DEBUG"

# OSErrors that are always about a path the user gave (other OSErrors count as bad input
# when they name a file, else as internal errors)
_PATH_ERRORS = (FileNotFoundError, FileExistsError, IsADirectoryError, NotADirectoryError,
                PermissionError)
# what a click context has (typer vendors click: duck-typed, no click import)
_CONTEXT = ("info_name", "parent", "command", "params")


def classify(exc: BaseException) -> tuple[int, str]:
    """The exit code and the one-line message for an exception a command raised."""
    if isinstance(exc, DepartureError):
        return EXIT_PHYSICAL, f"the flight departed: {exc}"
    if isinstance(exc, TrimInputError):
        return EXIT_BAD_INPUT, str(exc)
    if isinstance(exc, TrimError):
        return EXIT_PHYSICAL, str(exc)
    if isinstance(exc, NotConvergedError):
        return EXIT_NOT_CONVERGED, str(exc)
    if isinstance(exc, TimeoutError):  # a bridge link that never delivered
        return EXIT_PHYSICAL, str(exc)
    if isinstance(exc, np.linalg.LinAlgError):  # a ValueError, but a numerical failure
        return EXIT_INTERNAL, _internal(exc)
    if isinstance(exc, UnicodeDecodeError):
        return EXIT_BAD_INPUT, f"not a UTF-8 text file ({exc})"
    if isinstance(exc, CardError | ValueError):
        return EXIT_BAD_INPUT, str(exc)
    if isinstance(exc, KeyError):
        return EXIT_BAD_INPUT, str(exc.args[0]) if exc.args else "missing key"
    if isinstance(exc, OSError) and (isinstance(exc, _PATH_ERRORS) or exc.filename
                                     or str(exc).startswith("cannot write ")):
        if exc.strerror and exc.filename:  # as raised by open(): name the file first
            return EXIT_BAD_INPUT, f"{exc.filename}: {exc.strerror[0].lower()}{exc.strerror[1:]}"
        return EXIT_BAD_INPUT, str(exc)
    return EXIT_INTERNAL, _internal(exc)


def _internal(exc: BaseException) -> str:
    return (f"internal error: {type(exc).__name__}: {exc}; "
            "run with --debug for the traceback")


def _debug_env() -> bool:
    return os.environ.get(DEBUG_ENV, "").strip().lower() in ("1", "true", "yes", "on")


def _command_path(ctx: typer.Context, exc: BaseException) -> str:
    """The command that failed, e.g. ``simulate`` or ``bridge record``: the innermost click
    context on the traceback, else the group's invoked subcommand."""
    path = ctx.invoked_subcommand or ""
    tb: TracebackType | None = exc.__traceback__
    while tb is not None:
        sub = tb.tb_frame.f_locals.get("ctx")
        if all(hasattr(sub, a) for a in _CONTEXT) and sub.parent is not None:
            names, c = [], sub
            while c.parent is not None:
                names.append(c.info_name or "")
                c = c.parent
            path = " ".join(reversed(names))
        tb = tb.tb_next
    return path


class PolicyGroup(TyperGroup):
    """The top-level group: applies the error policy to whatever a command raises, so that
    ``flightid`` and ``CliRunner().invoke(app, ...)`` behave the same."""

    def invoke(self, ctx: typer.Context):
        try:
            return super().invoke(ctx)
        except (TyperException, typer.Exit, typer.Abort):
            raise  # usage errors (exit 2), typer.Exit and aborts keep their own handling
        except Exception as exc:
            if ctx.params.get("debug") or _debug_env():
                raise
            code, message = classify(exc)
            command = _command_path(ctx, exc)
            typer.echo(f"flightid {command}: {message}" if command else f"flightid: {message}",
                       err=True)
            raise typer.Exit(code) from None


app = typer.Typer(
    cls=PolicyGroup,
    pretty_exceptions_enable=False,
    help="flightid: aircraft system identification testbed (JSBSim truth flights, "
    "flight-test inputs, identification scored against known derivatives).",
    no_args_is_help=True,
    add_completion=False,
)


@app.callback()
def _main(debug: bool = typer.Option(
        False, "--debug", help=f"show the full traceback of an error (or {DEBUG_ENV}=1)")
          ) -> None:
    """flightid: aircraft system identification testbed.

    Exit codes: 0 success, 1 internal error, 2 bad input or usage, 3 physical failure
    (trim, departure, bridge timeout)."""


@app.command()
def version() -> None:
    """Print the flightid version."""
    typer.echo(__version__)


app.command("demo")(demo_command)


app.command("identify")(identify_command)
app.command("methods")(methods_command)


app.command("frequency-response")(frequency_response_command)
app.command("trim")(trim_command)
app.command("truth")(truth_command)
app.add_typer(bridge.app, name="bridge")
app.command("convert")(bridge.convert_command)
app.command("import")(import_command)
app.command("simulate")(simulate_command)
app.command("compatibility")(compatibility_command)
app.command("effects")(effects_command)
app.command("gap")(gap_command)
app.command("gap-benchmark")(gap_benchmark_command)
app.command("montecarlo")(montecarlo_command)
app.command("montecarlo-report")(montecarlo_report_command)
app.command("design-compare")(design_compare_command)
app.command("design-optimize")(design_optimize_command)
app.command("study-compare")(study_compare_command)


def main() -> None:
    """The console entry point. ``--debug`` is accepted anywhere on the command line (it is
    moved in front of the command, where the app's option lives); anything the policy of
    :class:`PolicyGroup` did not see ends as an internal error, exit 1."""
    args = sys.argv[1:]
    cut = args.index("--") if "--" in args else len(args)
    debug = "--debug" in args[:cut] or _debug_env()
    if "--debug" in args[:cut]:
        args = ["--debug", *(a for a in args[:cut] if a != "--debug"), *args[cut:]]
    try:
        app(args=args)
    except Exception as exc:
        if debug:
            raise
        print(f"flightid: {_internal(exc)}", file=sys.stderr)
        sys.exit(EXIT_INTERNAL)


if __name__ == "__main__":
    main()
