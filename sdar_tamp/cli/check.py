"""``sdar check``: parse PDDL and stream files and summarise what is in them."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from sdar_tamp.textfile import read_text


def cmd_check(args: argparse.Namespace) -> int:
    """Parse a domain (and optionally a problem and stream files); report what is in them.

    The stream files are checked against the domain (:mod:`sdar_tamp.language.cross_check`):
    a certified predicate nothing reads, and (given a problem) a predicate the domain reads
    that nothing makes true, are printed as located warnings; ``--strict`` makes them (and
    every parser leniency) errors."""
    from sdar_tamp.language import parse_domain, parse_problem, parse_stream_file
    from sdar_tamp.language.cross_check import cross_check, has_streams
    from sdar_tamp.language.stream_model import StreamFile

    strict = args.strict
    domain = parse_domain(read_text(args.domain), str(args.domain), strict=strict)
    print(
        f"domain {domain.name}: {len(domain.types.parents)} types, "
        f"{len(domain.predicates)} predicates, {len(domain.actions)} actions, "
        f"{len(domain.axioms)} axioms"
    )
    merged: StreamFile | None = None
    for path in args.streams:
        streams = parse_stream_file(read_text(path), domain, str(path), strict=strict)
        print(
            f"stream file {streams.name}: {len(streams.streams)} streams, "
            f"{len(streams.functions)} functions, {len(streams.predicates)} predicates, "
            f"{len(streams.rules)} rules"
        )
        merged = streams if merged is None else merged.merged(streams)
    problem = None
    if args.problem is not None:
        problem = parse_problem(read_text(args.problem), domain, str(args.problem), strict=strict)
        print(f"problem {problem.name}: {len(problem.objects)} objects, {len(problem.init)} facts")
    if merged is None or not has_streams(merged):
        return 0
    warnings = cross_check(
        domain,
        merged,
        None if problem is None else problem.init,
        None if problem is None else problem.goal,
    )
    for warning in warnings:
        print(f"sdar: warning: {warning}", file=sys.stderr)
    if strict and warnings:
        print(
            f"sdar: error: --strict: {len(warnings)} warning(s) from checking the stream files "
            "against the domain",
            file=sys.stderr,
        )
        return 2
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
    check.add_argument(
        "--strict",
        action="store_true",
        help="reject what strict PDDL rejects, and the stream files' cross-check warnings",
    )
    check.set_defaults(func=cmd_check)
