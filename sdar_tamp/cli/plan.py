"""``sdar plan``: classical planning on a PDDL domain and problem file."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sdar_tamp.arguments import SEARCH_WEIGHT, TIME_LIMIT
from sdar_tamp.textfile import read_text

if TYPE_CHECKING:
    from sdar_tamp.language.domain_model import Domain, Problem
    from solvers.classical import GroundAction


def cmd_plan(args: argparse.Namespace) -> int:
    """Classical planning on a PDDL domain and problem file."""
    from sdar_tamp.language import StrictModeError, parse_domain, parse_problem
    from solvers.classical import PlanStatus, plan, task_from_problem

    try:
        domain = parse_domain(read_text(args.domain), str(args.domain), strict=args.strict)
        problem = parse_problem(
            read_text(args.problem), domain, str(args.problem), strict=args.strict
        )
    except StrictModeError as error:
        for leniency in error.leniencies:
            print(f"sdar: warning: {leniency}", file=sys.stderr)
        print(
            f"sdar: error: --strict: {len(error.leniencies)} warning(s); without --strict "
            "these constructs are accepted",
            file=sys.stderr,
        )
        return 2
    if args.planner == "fd" and domain.temporal:  # Fast Downward reads no durative action
        from solvers.classical.fast_downward import plan_task_with_fast_downward

        if args.unit:
            print("sdar: error: --unit is not available with --planner fd", file=sys.stderr)
            return 2
        result = plan_task_with_fast_downward(
            task_from_problem(domain, problem),
            search=args.search,
            heuristic=args.heuristic,
            weight=args.weight,
            time_limit=args.time_limit,
        )
    elif args.planner == "fd":
        from solvers.classical.fast_downward import plan_with_fast_downward

        if args.unit:
            print("sdar: error: --unit is not available with --planner fd", file=sys.stderr)
            return 2
        result = plan_with_fast_downward(
            args.domain,
            args.problem,
            search=args.search,
            heuristic=args.heuristic,
            weight=args.weight,
            time_limit=args.time_limit,
        )
    else:
        result = plan(
            task_from_problem(domain, problem, use_costs=False if args.unit else None),
            search=args.search,
            heuristic=args.heuristic,
            weight=args.weight,
            time_limit=args.time_limit,
            exploration=False if args.no_exploration else None,
        )
    stats = result.statistics
    print(f"status: {result.status.value}")
    if result.plan is not None and domain.temporal:
        for line in timed_plan_lines(domain, problem, result.plan):
            print(line)
        print(f"length: {len(result.plan)}  cost: {result.cost:g}")
    elif result.plan is not None:
        for step, action in enumerate(result.plan, 1):
            print(f"{step:3d}) {action}")
        print(f"length: {len(result.plan)}  cost: {result.cost:g}")
    print(
        f"expanded: {stats.expanded}  generated: {stats.generated}  "
        f"grounding: {stats.grounding_time:.3f} s  search: {stats.search_time:.3f} s"
    )
    return 0 if result.status is PlanStatus.SOLVED else 1


def timed_plan_lines(domain: Domain, problem: Problem, steps: Sequence[GroundAction]) -> list[str]:
    """A plan of a domain with durative actions in VAL's format, ``START: (ACTION) [DURATION]``
    a line (steps one after the other; durations from the problem's function values)."""
    from sdar_tamp.language.formula_model import FunctionTerm
    from sdar_tamp.language.plan_run import plan_timing

    def value(term: FunctionTerm) -> float:
        return problem.numeric_init[(term.name, term.args)]

    timing = plan_timing(domain, [(a.name, a.args) for a in steps], value)
    return [
        f"{start:.3f}: ({' '.join((a.name, *a.args))}) [{length:.3f}]"
        for a, (start, length) in zip(steps, timing, strict=True)
    ]


def add_plan_parser(sub: argparse._SubParsersAction[Any]) -> None:
    """Register ``sdar plan``."""
    plan = sub.add_parser(
        "plan", help="classical planning on PDDL files", description=cmd_plan.__doc__
    )
    plan.add_argument("domain", type=Path, help="domain.pddl")
    plan.add_argument("problem", type=Path, help="problem.pddl")
    plan.add_argument(
        "--search",
        choices=("lazy-gbfs", "gbfs", "astar", "wastar"),
        default="lazy-gbfs",
        help="(default: lazy-gbfs, greedy with lazy evaluation as LAMA's first iteration)",
    )
    plan.add_argument(
        "--heuristic",
        choices=("ff-lmcount", "ff", "lmcount", "add", "max", "blind"),
        default="ff-lmcount",
        help="(default: ff-lmcount, h_FF and landmark count in alternating queues)",
    )
    plan.add_argument(
        "--planner",
        choices=("sdar", "fd"),
        default="sdar",
        help="sdar: this package's planner (default); fd: Fast Downward "
        "(pip install sdar-tamp[fd]), which runs its own lama-first for lazy-gbfs with "
        "ff-lmcount, else the chosen search and heuristic",
    )
    plan.add_argument(
        "--weight",
        type=SEARCH_WEIGHT.parse,
        default=2.0,
        help="weight of wastar, >= 1 (default: 2)",
    )
    plan.add_argument(
        "--time-limit", type=TIME_LIMIT.parse, default=None, help="seconds (default: none)"
    )
    plan.add_argument("--unit", action="store_true", help="ignore action costs")
    plan.add_argument(
        "--no-exploration",
        action="store_true",
        help="lazy-gbfs without its type-based exploration queue (the heuristic queues only)",
    )
    plan.add_argument(
        "--strict",
        action="store_true",
        help="reject what Fast Downward and VAL accept beyond standard PDDL (glued '?x', "
        "undeclared or twice-declared predicates...): print each as a warning, exit 2",
    )
    plan.set_defaults(func=cmd_plan)
