"""The ``footfall`` command line.

One module per subcommand, each parsing its options into a request, calling the library's
``run_*`` function (:mod:`footfall.reports`) and printing the report. A subcommand's module
(and what it imports: the simulator, the SDKs) loads only when that command is run or its
help asked for; ``footfall --help`` lists the commands from :mod:`footfall.cli.commands`.
"""

from __future__ import annotations

import argparse
import faulthandler
import importlib
import signal
import sys

from footfall.cli.commands import COMMANDS
from footfall.errors import FootfallError


def build_parser(command: str | None = None, brief: bool = False) -> argparse.ArgumentParser:
    """The ``footfall`` argument parser.

    Args:
        command: Build only this subcommand's options (the others are listed by name and
            help); None: every subcommand's.
        brief: List every subcommand by name and help alone (``footfall --help``).
    """
    parser = argparse.ArgumentParser(
        prog="footfall",
        description="Legged robots walking over uneven terrain, simulated and recorded.",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, (module, help_text) in COMMANDS.items():
        if brief or (command is not None and name != command):
            subparsers.add_parser(name, help=help_text)
        else:
            importlib.import_module(module).add_parser(subparsers)
    return parser


def _stacks_on_sigusr1() -> None:
    """Have `kill -USR1 PID` print every thread's stack to stderr.

    Where a robot or station process that will not stop is stuck, without stopping it.
    """
    if not hasattr(signal, "SIGUSR1"):
        return
    try:
        faulthandler.register(signal.SIGUSR1, file=sys.stderr, all_threads=True)
    except (AttributeError, OSError, ValueError):  # io.UnsupportedOperation: no file behind it
        pass  # called in a process whose stderr is not a file (a test capturing it)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``footfall`` console script."""
    argv = sys.argv[1:] if argv is None else argv
    command = next((a for a in argv if not a.startswith("-")), None)
    if command in COMMANDS:
        parser = build_parser(command)
    else:  # no command, --help, or an unknown one: the list is all that is needed
        parser = build_parser(brief=True)
    args = parser.parse_args(argv)
    _stacks_on_sigusr1()
    from rich.console import Console

    console = Console()
    try:
        return args.handler(args, console)
    except FootfallError as exc:
        console.print(f"[red]error:[/] {exc}")
        return 2
