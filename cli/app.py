"""The ``flightid`` command line: the commands of every group wired into one typer app.

The command bodies live in one module per command group (``flightid.cli.trim_truth``,
``simulate``, ``bridge``, ``frequency_response``, ``compatibility``); ``identify`` and
``demo`` still call the ``run_cli`` of their library modules.
"""

from __future__ import annotations

import sys

import typer

from flightid import __version__
from flightid.cli import bridge
from flightid.cli.compatibility import compatibility_command
from flightid.cli.demo import demo_command
from flightid.cli.effects import effects_command
from flightid.cli.frequency_response import frequency_response_command
from flightid.cli.identify import identify_command
from flightid.cli.methods import methods_command
from flightid.cli.simulate import simulate_command
from flightid.cli.trim_truth import trim_command, truth_command

app = typer.Typer(
    pretty_exceptions_enable=False,
    help="flightid: aircraft system identification testbed (JSBSim truth flights, "
    "flight-test inputs, identification scored against known derivatives).",
    no_args_is_help=True,
    add_completion=False,
)


@app.callback()
def _main() -> None:
    """flightid: aircraft system identification testbed."""


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
app.command("simulate")(simulate_command)
app.command("compatibility")(compatibility_command)
app.command("effects")(effects_command)


def main() -> None:
    """The console entry point: bad input ends in one clear line and exit code 2."""
    try:
        app()
    except (ValueError, KeyError, FileNotFoundError, NotADirectoryError, IsADirectoryError) as exc:
        command = " ".join(a for a in sys.argv[1:2] if not a.startswith("-"))
        message = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        print(f"flightid {command}: {message}".replace("  ", " "), file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    main()
