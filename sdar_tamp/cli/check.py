"""``sdar check``: parse PDDL and stream files and summarise what is in them."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from sdar_tamp.textfile import read_text


def cmd_check(args: argparse.Namespace) -> int:
    """Parse a domain (and optionally a problem and stream files); report what is in them."""
    from sdar_tamp.language import parse_domain, parse_problem, parse_stream_file

    domain = parse_domain(read_text(args.domain), str(args.domain))
    print(
        f"domain {domain.name}: {len(domain.types.parents)} types, "
        f"{len(domain.predicates)} predicates, {len(domain.actions)} actions, "
        f"{len(domain.axioms)} axioms"
    )
    for path in args.streams:
        streams = parse_stream_file(read_text(path), domain, str(path))
        print(
            f"stream file {streams.name}: {len(streams.streams)} streams, "
            f"{len(streams.functions)} functions, {len(streams.predicates)} predicates, "
            f"{len(streams.rules)} rules"
        )
    if args.problem is not None:
        problem = parse_problem(read_text(args.problem), domain, str(args.problem))
        print(f"problem {problem.name}: {len(problem.objects)} objects, {len(problem.init)} facts")
    return 0


def add_check_parser(sub: argparse._SubParsersAction[Any]) -> None:
    """Register ``sdar check``."""
    check = sub.add_parser(
        "check", help="parse and summarise PDDL and stream files", description=cmd_check.__doc__
    )
    check.add_argument("domain", type=Path, help="domain.pddl")
    check.add_argument("problem", type=Path, nargs="?", default=None, help="problem.pddl")
    check.add_argument(
        "--streams", type=Path, action="append", default=[], help="a stream file (repeatable)"
    )
    check.set_defaults(func=cmd_check)
