"""The ``flightid`` command line: the commands of every group wired into one typer app,
and the one error policy of the command line (docs/errors.md).

The command bodies live in one module per command group (``flightid.cli.trim_truth``,
``simulate``, ``bridge``, ``frequency_response``, ``compatibility``); ``identify`` and
``demo`` still call the ``run_cli`` of their library modules. ``COMMANDS`` lists them; a
command's module is imported only when it runs, so ``flightid --help`` stays light.

Exit codes: 0 success; 1 internal error (a bug: one line naming the exception); 2 bad input
or usage (a missing or unreadable file, a bad option, a malformed card, an output that
cannot be written); 3 physical failure (the aircraft cannot be trimmed, the flight
departed, a bridge link never delivered). ``--debug`` (or ``FLIGHTID_DEBUG=1``) re-raises
with the full traceback; without it no traceback is ever printed.
"""

from __future__ import annotations

import ast
import functools
import os
import sys
from difflib import get_close_matches
from importlib import import_module
from importlib.util import find_spec
from pathlib import Path
from types import TracebackType

import numpy as np
import typer
import typer.main
from typer.core import TyperCommand, TyperGroup
from typer.exceptions import TyperException
from typer.models import CommandInfo

from flightid import __version__

# every command but ``version``, in the order of ``flightid --help``: {name: (module,
# attribute)}. A command's module is imported only when the command runs; ``--help`` reads
# the commands' help from their source (the function's docstring, the group's ``help=``)
COMMANDS = {
    "demo": ("flightid.cli.demo", "demo_command"),
    "identify": ("flightid.cli.identify", "identify_command"),
    "methods": ("flightid.cli.methods", "methods_command"),
    "frequency-response": ("flightid.cli.frequency_response", "frequency_response_command"),
    "trim": ("flightid.cli.trim_truth", "trim_command"),
    "truth": ("flightid.cli.trim_truth", "truth_command"),
    "convert": ("flightid.cli.bridge", "convert_command"),
    "import": ("flightid.cli.importing", "import_command"),
    "simulate": ("flightid.cli.simulate", "simulate_command"),
    "compatibility": ("flightid.cli.compatibility", "compatibility_command"),
    "effects": ("flightid.cli.effects", "effects_command"),
    "gap": ("flightid.cli.gap", "gap_command"),
    "gap-benchmark": ("flightid.cli.gap_benchmark", "gap_benchmark_command"),
    "montecarlo": ("flightid.cli.montecarlo", "montecarlo_command"),
    "montecarlo-report": ("flightid.cli.montecarlo", "montecarlo_report_command"),
    "design-compare": ("flightid.cli.design_compare", "design_compare_command"),
    "design-optimize": ("flightid.cli.design_optimize", "design_optimize_command"),
    "study-compare": ("flightid.cli.study_compare", "study_compare_command"),
    "campaign": ("flightid.cli.campaign", "campaign_command"),
    "bridge": ("flightid.cli.bridge", "app"),
}
# the exceptions of the library that the policy classifies: {name: module}. An exception
# of a module that is not loaded cannot have been raised, so the policy looks them up in
# sys.modules instead of importing the simulator and the methods for every command
_CLASSIFIED = {
    "DepartureError": "flightid.sim.flight.simulation",
    "TrimInputError": "flightid.sim.jsbsim.trim",
    "TrimError": "flightid.sim.jsbsim.trim",
    "NotConvergedError": "flightid.identification.engine.convergence",
    "CardError": "flightid.scenarios.cards",
}

EXIT_OK, EXIT_INTERNAL, EXIT_BAD_INPUT, EXIT_PHYSICAL = 0, 1, 2, 3
EXIT_NOT_CONVERGED = 4  # --strict and an iterative fit that did not converge
DEBUG_ENV = "FLIGHTID_DEBUG"

# OSErrors that are always about a path the user gave (other OSErrors count as bad input
# when they name a file, else as internal errors)
_PATH_ERRORS = (FileNotFoundError, FileExistsError, IsADirectoryError, NotADirectoryError,
                PermissionError)
# what a click context has (typer vendors click: duck-typed, no click import)
_CONTEXT = ("info_name", "parent", "command", "params")


def _is(exc: BaseException, name: str) -> bool:
    """Whether ``exc`` is a ``name`` of ``_CLASSIFIED`` (False while its module is not loaded)."""
    cls = getattr(sys.modules.get(_CLASSIFIED[name]), name, None)
    return cls is not None and isinstance(exc, cls)


def classify(exc: BaseException) -> tuple[int, str]:
    """The exit code and the one-line message for an exception a command raised."""
    if _is(exc, "DepartureError"):
        return EXIT_PHYSICAL, f"the flight departed: {exc}"
    if _is(exc, "TrimInputError"):
        return EXIT_BAD_INPUT, str(exc)
    if _is(exc, "TrimError"):
        return EXIT_PHYSICAL, str(exc)
    if _is(exc, "NotConvergedError"):
        return EXIT_NOT_CONVERGED, str(exc)
    if isinstance(exc, TimeoutError):  # a bridge link that never delivered
        return EXIT_PHYSICAL, str(exc)
    if isinstance(exc, np.linalg.LinAlgError):  # a ValueError, but a numerical failure
        return EXIT_INTERNAL, _internal(exc)
    if isinstance(exc, UnicodeDecodeError):
        return EXIT_BAD_INPUT, f"not a UTF-8 text file ({exc})"
    if _is(exc, "CardError") or isinstance(exc, ValueError):
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

    def list_commands(self, ctx: typer.Context) -> list[str]:
        return [*super().list_commands(ctx), *COMMANDS]

    def get_command(self, ctx: typer.Context, cmd_name: str):
        if cmd_name not in COMMANDS:
            return super().get_command(ctx, cmd_name)
        if getattr(self, "_listing", False):  # --help: the help text, nothing imported
            return TyperCommand(cmd_name, help=_help_in_source(*COMMANDS[cmd_name]))
        return _load_command(cmd_name)

    def format_help(self, ctx: typer.Context, formatter) -> None:
        self._listing = True
        try:
            super().format_help(ctx, formatter)
        finally:
            self._listing = False

    def resolve_command(self, ctx: typer.Context, args: list[str]):
        try:
            return super().resolve_command(ctx, args)
        except TyperException as e:  # "No such command": suggest the lazy commands too
            matches = get_close_matches(args[0], self.list_commands(ctx)) if args else []
            if matches and hasattr(e, "message") and "Did you mean" not in e.message:
                suggestions = ", ".join(f"{m!r}" for m in matches)
                e.message = f"{e.message.rstrip('.')}. Did you mean {suggestions}?"
            raise


def _load_command(name: str):
    """The click command (or group) of ``COMMANDS[name]``, its module imported now."""
    module, attribute = COMMANDS[name]
    target = getattr(import_module(module), attribute)
    if isinstance(target, typer.Typer):
        command = typer.main.get_group(target)
        command.name = name
        return command
    return typer.main.get_command_from_info(
        CommandInfo(name=name, callback=target),
        pretty_exceptions_short=app.pretty_exceptions_short,
        rich_markup_mode=app.rich_markup_mode)


@functools.cache
def _source_tree(module: str) -> ast.Module:
    """The syntax tree of ``module``'s source, read without importing it."""
    return ast.parse(Path(find_spec(module).origin).read_text(encoding="utf-8"))


def _help_in_source(module: str, attribute: str) -> str:
    """The help of a command without importing it: the docstring of function ``attribute``
    of ``module``, or the ``help=`` of the typer app assigned to ``attribute``."""
    for node in _source_tree(module).body:
        if isinstance(node, ast.FunctionDef) and node.name == attribute:
            return ast.get_docstring(node) or ""
        if (isinstance(node, ast.Assign) and isinstance(node.value, ast.Call)
                and any(getattr(t, "id", None) == attribute for t in node.targets)):
            for keyword in node.value.keywords:
                if keyword.arg == "help":
                    return ast.literal_eval(keyword.value)
    return ""


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
