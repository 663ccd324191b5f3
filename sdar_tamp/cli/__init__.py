"""The ``sdar`` command line: the parser, built from one module per command, and :func:`main`.

Each command's module holds its parser and the function that runs it; the library functions
behind them return values, and the commands print them and choose the exit status. Heavy
modules are imported inside the commands that need them, so ``sdar --help`` starts fast.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from typing import NoReturn

from sdar_tamp import __version__
from sdar_tamp.cli.bench import add_bench_parser
from sdar_tamp.cli.cells import add_cells_parser
from sdar_tamp.cli.check import add_check_parser
from sdar_tamp.cli.demo import add_demo_parser
from sdar_tamp.cli.export import add_export_parser
from sdar_tamp.cli.generate import add_generate_parser
from sdar_tamp.cli.log_options import add_logging_options, configure_logging
from sdar_tamp.cli.plan import add_plan_parser
from sdar_tamp.cli.replan import add_replan_parser
from sdar_tamp.cli.show import add_show_parser
from sdar_tamp.cli.solve import add_solve_parser
from sdar_tamp.cli.validate import add_validate_parser
from sdar_tamp.errors import SdarError

__all__ = ["build_parser", "main"]


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line: ``sdar solve: error: ... (see --help)``."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="sdar",
        description="Declarative task-and-motion planning with PDDL streams.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for add in (
        add_plan_parser,
        add_check_parser,
        add_generate_parser,
        add_solve_parser,
        add_replan_parser,
        add_show_parser,
        add_validate_parser,
        add_bench_parser,
        add_cells_parser,
        add_demo_parser,
        add_export_parser,
    ):
        add(sub)
    for command in sub.choices.values():
        add_logging_options(command)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    func: Callable[[argparse.Namespace], int] = args.func
    configure_logging(args)
    try:
        return func(args)
    except SdarError as error:
        print(f"sdar: error: {error}", file=sys.stderr)
        return 2
    except OSError as error:  # a file that could not be read or written after the checks
        where = f"{error.filename}: " if error.filename else ""
        print(f"sdar: error: {where}{error.strerror or error}", file=sys.stderr)
        return 2
