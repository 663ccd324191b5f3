"""The logging options every command takes (``-v``, ``--log-level``) and what they set."""

from __future__ import annotations

import argparse
import logging
import sys
from typing import Any

LOG_LEVELS = ("debug", "info", "warning", "error")
#: Help texts shared by several commands.
FORCE_HELP = "replace output files that exist (default: refuse)"
JSON_HELP = "print one JSON object (machine-readable) instead of the text summary"
SCENE_HELP = "a scene file (cell) replacing the instances' own scene (see `sdar cells`)"


def add_logging_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("logging")
    group.add_argument(
        "-v",
        "--verbose",
        action="count",
        default=0,
        help="more log lines on stderr: -v info, -vv debug (default: warnings only)",
    )
    group.add_argument(
        "--log-level", choices=LOG_LEVELS, default=None, help="log level (overrides -v)"
    )


def configure_logging(args: argparse.Namespace) -> None:
    """With ``-v`` or ``--log-level`` the program shows the package's log lines of that level on
    stderr; without them logging is left as it is (Python shows warnings and errors)."""
    verbose = getattr(args, "verbose", 0)
    name = args.log_level or (None, "info", "debug")[min(verbose, 2)]
    if name is None:
        return
    logging.basicConfig(format="%(levelname)s %(name)s: %(message)s", handlers=[_Stderr()])
    logging.getLogger("sdar_tamp").setLevel(name.upper())


class _Stderr(logging.StreamHandler):  # type: ignore[type-arg]
    """A handler writing to whatever ``sys.stderr`` is when a record comes (not the stream of
    the moment it was made, which may be closed by then)."""

    @property
    def stream(self) -> Any:
        return sys.stderr

    @stream.setter
    def stream(self, value: Any) -> None:
        pass
