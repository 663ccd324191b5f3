"""The ``sdar`` command line. Heavy modules are imported inside the commands that need them."""

from __future__ import annotations

import argparse
import json
import logging
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NoReturn

from sdar_tamp import __version__
from sdar_tamp.arguments import (
    COUNT,
    FPS,
    SEARCH_WEIGHT,
    SEED,
    TIME_LIMIT,
    output_file,
    output_folder,
)
from sdar_tamp.errors import SdarError
from sdar_tamp.export.command import add_export_parser
from sdar_tamp.textfile import read_text

#: The generator's families and the named suites, spelt out so that the command line starts
#: without NumPy (tests/cli checks they match sdar_tamp.world.generators and .suites).
CLI_FAMILIES = ("R", "S", "D", "M", "N")
CLI_SUITES = ("paper", "stress", "dense")

DEMO_DOMAIN = "dual_arm_rearrangement"
DEMO_INSTANCE = "suites/paper/M1.yaml"
_FORCE = "replace output files that exist (default: refuse)"
_JSON = "print one JSON object (machine-readable) instead of the text summary"


def _read(path: Path) -> str:
    return read_text(path)


def cmd_plan(args: argparse.Namespace) -> int:
    """Classical planning on a PDDL domain and problem file."""
    from sdar_tamp.language import StrictModeError, parse_domain, parse_problem
    from solvers.classical import PlanStatus, plan, task_from_problem

    try:
        domain = parse_domain(_read(args.domain), str(args.domain), strict=args.strict)
        problem = parse_problem(_read(args.problem), domain, str(args.problem), strict=args.strict)
    except StrictModeError as error:
        for leniency in error.leniencies:
            print(f"sdar: warning: {leniency}", file=sys.stderr)
        print(
            f"sdar: error: --strict: {len(error.leniencies)} warning(s); without --strict "
            "these constructs are accepted",
            file=sys.stderr,
        )
        return 2
    if args.planner == "fd":
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
    if result.plan is not None:
        for step, action in enumerate(result.plan, 1):
            print(f"{step:3d}) {action}")
        print(f"length: {len(result.plan)}  cost: {result.cost:g}")
    print(
        f"expanded: {stats.expanded}  generated: {stats.generated}  "
        f"grounding: {stats.grounding_time:.3f} s  search: {stats.search_time:.3f} s"
    )
    return 0 if result.status is PlanStatus.SOLVED else 1


def cmd_check(args: argparse.Namespace) -> int:
    """Parse a domain (and optionally a problem and stream files); report what is in them."""
    from sdar_tamp.language import parse_domain, parse_problem, parse_stream_file

    domain = parse_domain(_read(args.domain), str(args.domain))
    print(
        f"domain {domain.name}: {len(domain.types.parents)} types, "
        f"{len(domain.predicates)} predicates, {len(domain.actions)} actions, "
        f"{len(domain.axioms)} axioms"
    )
    for path in args.streams:
        streams = parse_stream_file(_read(path), domain, str(path))
        print(
            f"stream file {streams.name}: {len(streams.streams)} streams, "
            f"{len(streams.functions)} functions, {len(streams.predicates)} predicates, "
            f"{len(streams.rules)} rules"
        )
    if args.problem is not None:
        problem = parse_problem(_read(args.problem), domain, str(args.problem))
        print(f"problem {problem.name}: {len(problem.objects)} objects, {len(problem.init)} facts")
    return 0


def cmd_demo(args: argparse.Namespace) -> int:
    """Solve the shipped 12-object mixed instance M1 with SDAR as ``sdar solve`` does
    (asynchronous execution), validate the plan by replay, and write the plan file, the 3-D
    page and the storyboard (default: a folder in the system's temporary directory; nothing
    is written to the working directory)."""
    import tempfile

    from sdar_tamp.app.pipeline import solve_instance
    from sdar_tamp.app.summary import ProgressBar, format_summary
    from sdar_tamp.plan_file import save_plan
    from sdar_tamp.resources import domain_file
    from sdar_tamp.viewer import write_html, write_storyboard

    instance = domain_file(DEMO_DOMAIN, DEMO_INSTANCE)
    if args.output is None:
        out = Path(tempfile.mkdtemp(prefix="sdar-demo-"))  # a fresh folder per run
    else:
        out = output_folder(args.output, name="--output")
        out.mkdir(parents=True, exist_ok=True)
    print(f"Solving the shipped mixed instance {DEMO_INSTANCE} (12 objects) with SDAR:")
    bar = ProgressBar(instance.stem)
    try:
        outcome = solve_instance(
            instance,
            time_limit=args.time_limit,
            execution="async",  # `sdar solve`'s default
            progress=bar,
            stage=bar.stage,
        )
    finally:
        bar.close()
    print(format_summary(outcome))
    if outcome.plan is None:
        return 1
    print(f"wrote {save_plan(outcome.plan, out / 'plan.json')}")
    print(f"wrote {write_html(outcome.instance, outcome.plan, out / 'plan.html')}")
    print(f"wrote {write_storyboard(outcome.instance, outcome.plan, out / 'storyboard.png')}")
    print(f"check it again with: sdar validate {instance} {out / 'plan.json'}")
    return 0 if outcome.success else 1


def cmd_solve(args: argparse.Namespace) -> int:
    """Plan a rearrangement instance with SDAR, validate the plan by independent replay and
    write it (JSON, see the README). Exit status 0 only when solved and valid."""
    import dataclasses

    from sdar_tamp.app.config import PlannerConfig
    from sdar_tamp.app.pipeline import solve_instance
    from sdar_tamp.app.summary import ProgressBar, format_summary
    from sdar_tamp.plan_file import save_plan

    if args.output is not None:
        output_file(args.output, suffixes=(".json",), force=args.force)
    bar = ProgressBar(f"{args.instance.stem}") if not (args.quiet or args.json) else None
    try:
        config = PlannerConfig(
            task_planner=args.task_planner,
            motion_planner=args.motion_planner,
            max_time=args.time_limit,
            seed=args.seed,
            execution=args.execution,
        )
        if args.grasps is not None:
            config = config.replace(sdar=dataclasses.replace(config.sdar, grasps=args.grasps))
        outcome = solve_instance(
            args.instance, config, progress=bar, stage=bar.stage if bar is not None else None
        )
    finally:
        if bar is not None:
            bar.close()
    written = None
    if outcome.plan is not None and args.output is not None:
        written = save_plan(outcome.plan, args.output)
    if args.json:
        from sdar_tamp.app.summary import summary_record

        record = summary_record(outcome, plan_file=written)
        print(json.dumps(record, sort_keys=True))
    else:
        print(format_summary(outcome))
        if written is not None:
            print(f"wrote {written}")
    return 0 if outcome.success else 1


def cmd_generate(args: argparse.Namespace) -> int:
    """Generate a rearrangement instance (one family) or a whole suite of instance files."""
    from sdar_tamp.world.commands import generate, generate_suite, suite_files
    from streams.feasibility import ProofCheck  # refuses samples proven unsolvable

    if args.suite is not None:
        if args.family is not None or args.objects is not None:
            raise SdarError("sdar generate: --suite cannot be combined with --family/--objects")
        output_folder(args.output)
        taken = [p for p in suite_files(args.suite, args.output) if p.exists()]
        if taken and not args.force:
            raise SdarError(
                f"--output: {len(taken)} instance file(s) of suite {args.suite!r} exist in "
                f"{str(args.output)!r} (e.g. {taken[0].name}); pass --force to replace them"
            )
        paths = generate_suite(args.suite, args.output, ProofCheck())
        print(f"wrote {len(paths)} instances of suite {args.suite!r} to {args.output}")
        return 0
    if args.family is None or args.objects is None:
        raise SdarError("sdar generate needs --family and --objects, or --suite")
    output_file(args.output, suffixes=(".yaml", ".yml"), force=args.force)
    path = generate(args.family, args.objects, args.seed, args.output, ProofCheck())
    print(f"wrote {path}")
    return 0


def cmd_show(args: argparse.Namespace) -> int:
    """Draw an instance, or a plan on it.

    Without a plan: .png (or another matplotlib format) draws start and goal top-down with the
    dependency graph; .html is an interactive 3-D view of the start. With a plan: .html is an
    interactive 3-D replay (plotly, works offline), .png a storyboard with one panel per step,
    .gif a top-down animation."""
    from sdar_tamp.viewer.commands import check_output, show

    check_output(args.output, args.plan is not None)
    output_file(args.output, force=args.force)
    print(f"wrote {show(args.instance, args.plan, args.output, args.fps)}")
    return 0


def cmd_validate(args: argparse.Namespace) -> int:
    """Replay a plan file on an instance and check it independently of the planner."""
    from sdar_tamp.replay import run_validate

    return run_validate(args.instance, args.plan, as_json=args.json)


def cmd_bench(args: argparse.Namespace) -> int:
    """Run the paper's evaluation: every planner combination on every instance of a suite, in
    worker processes. One CSV row per finished run, then plots and a report in the output
    folder. A rerun with the same settings resumes (Ctrl-C keeps the finished runs); one with
    another seed, time limit, worker count or suite is refused unless --restart is given."""
    from sdar_tamp.evaluation.runner import bench_command

    return bench_command(args)


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

    check = sub.add_parser(
        "check", help="parse and summarise PDDL and stream files", description=cmd_check.__doc__
    )
    check.add_argument("domain", type=Path, help="domain.pddl")
    check.add_argument("problem", type=Path, nargs="?", default=None, help="problem.pddl")
    check.add_argument(
        "--streams", type=Path, action="append", default=[], help="a stream file (repeatable)"
    )
    check.set_defaults(func=cmd_check)

    generate = sub.add_parser(
        "generate", help="generate rearrangement instances", description=cmd_generate.__doc__
    )
    generate.add_argument("--family", choices=CLI_FAMILIES, help="instance family")
    generate.add_argument("--objects", type=COUNT.parse, help="number of objects")
    generate.add_argument("--seed", type=SEED.parse, default=0, help="random seed (default: 0)")
    generate.add_argument("--suite", choices=CLI_SUITES, help="a whole suite")
    generate.add_argument(
        "-o",
        "--output",
        type=Path,
        required=True,
        help="instance file (.yaml), or folder with --suite",
    )
    generate.add_argument("--force", action="store_true", help=_FORCE)
    generate.set_defaults(func=cmd_generate)

    solve = sub.add_parser(
        "solve", help="plan a rearrangement instance with SDAR", description=cmd_solve.__doc__
    )
    solve.add_argument("instance", type=Path, help="instance YAML")
    solve.add_argument("-o", "--output", type=Path, default=None, help="plan file (.json)")
    solve.add_argument("--force", action="store_true", help=_FORCE)
    solve.add_argument(
        "--time-limit", type=TIME_LIMIT.parse, default=60.0, help="seconds (default: 60)"
    )
    solve.add_argument("--seed", type=SEED.parse, default=0, help="random seed (default: 0)")
    solve.add_argument(
        "--task-planner", choices=("sdar", "baseline"), default="sdar", help="(default: sdar)"
    )
    solve.add_argument(
        "--motion-planner",
        choices=("sdar", "plain", "sequential"),
        default="sdar",
        help="sdar: optimisation, untangling, one arm at a time; plain: optimisation only; "
        "sequential: one arm at a time (default: sdar)",
    )
    solve.add_argument(
        "--grasps",
        type=COUNT.parse,
        default=None,
        help="grasps tried per object, in the grasp set's order (default: 6)",
    )
    solve.add_argument(
        "--execution",
        choices=("sync", "async"),
        default="async",
        help="sync: both arms on one synchronous timeline; async: each arm on its own, "
        "re-timed for itself, kept only when shorter and valid (default: async)",
    )
    solve.add_argument("--json", action="store_true", help=_JSON + " (implies -q)")
    solve.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    solve.set_defaults(func=cmd_solve)

    show = sub.add_parser(
        "show",
        help="draw an instance, or replay a plan",
        description=cmd_show.__doc__,
    )
    show.add_argument("instance", type=Path, help="instance YAML")
    show.add_argument("plan", type=Path, nargs="?", default=None, help="plan JSON (optional)")
    show.add_argument(
        "-o",
        "--output",
        type=Path,
        required=True,
        help="picture: .png or .html (also .pdf, .svg, .jpg without a plan, .gif with one)",
    )
    show.add_argument("--force", action="store_true", help=_FORCE)
    show.add_argument(
        "--fps",
        type=FPS.parse,
        default=None,
        help="animation frames per second of plan time (default: 10 for .html, 4 for .gif)",
    )
    show.set_defaults(func=cmd_show)

    validate = sub.add_parser(
        "validate", help="check a plan file against an instance", description=cmd_validate.__doc__
    )
    validate.add_argument("instance", type=Path, help="instance YAML")
    validate.add_argument("plan", type=Path, help="plan JSON")
    validate.add_argument("--json", action="store_true", help=_JSON)
    validate.set_defaults(func=cmd_validate)

    bench = sub.add_parser(
        "bench", help="evaluate planner combinations on a suite", description=cmd_bench.__doc__
    )
    bench.add_argument(
        "--suite",
        default="paper",
        help="paper, stress, dense or a folder of instances (./NAME for a folder named like "
        "a shipped suite)",
    )
    bench.add_argument(
        "-o", "--output", "--out", dest="out", type=Path, required=True, help="output folder"
    )
    bench.add_argument(
        "--combos",
        default="all",
        help="all, or some of sdar,baseline,baseline-tp+sdar-m,sdar-t+baseline-mp,"
        "sdar-t+plain,baseline-tp+plain,sdar-async (default: all)",
    )
    bench.add_argument(
        "--workers",
        type=COUNT.parse,
        default=None,
        help="runs at once (default: 1 process; with --backend ray, one per cluster CPU)",
    )
    bench.add_argument(
        "--time-limit", type=TIME_LIMIT.parse, default=60.0, help="s per run (default: 60)"
    )
    bench.add_argument("--only", default="", help="comma-separated instance names")
    bench.add_argument(
        "--max-objects", type=COUNT.parse, default=None, help="skip larger instances"
    )
    bench.add_argument("--seed", type=SEED.parse, default=0, help="random seed (default: 0)")
    bench.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    bench.add_argument(
        "--restart",
        action="store_true",
        help="discard the runs already in --out (needed to change seed, time limit, workers "
        "or suite there; without it such a rerun is refused)",
    )
    bench.add_argument(
        "--backend",
        choices=("process", "ray"),
        default="process",
        help="process: worker processes here (default); ray: Ray tasks on a cluster, or on a "
        "local Ray (pip install 'sdar-tamp[cluster]')",
    )
    bench.add_argument(
        "--address",
        default=None,
        help="with --backend ray: the cluster's head, host:port (default: $RAY_ADDRESS, else "
        "a local Ray)",
    )
    bench.add_argument(
        "--shard",
        default=None,
        metavar="I/N",
        help="run only shard I of N (1 <= I <= N) of the (instance, combination) pairs, for "
        "batch schedulers; each shard into its own --out, joined with --merge",
    )
    bench.add_argument(
        "--merge",
        nargs="+",
        type=Path,
        default=None,
        metavar="DIR",
        help="join the folders of finished shards into --out (a new folder) and write its "
        "report; runs nothing, the other options are ignored",
    )
    bench.set_defaults(func=cmd_bench)

    demo = sub.add_parser("demo", help="solve a built-in example", description=cmd_demo.__doc__)
    demo.add_argument(
        "--time-limit", type=TIME_LIMIT.parse, default=60.0, help="seconds (default: 60)"
    )
    demo.add_argument(
        "-o",
        "--output",
        "--out",
        dest="output",
        type=Path,
        default=None,
        help="output folder (default: a new folder sdar-demo-* in the temporary directory)",
    )
    demo.set_defaults(func=cmd_demo)

    add_export_parser(sub)  # sdar export, defined in sdar_tamp/export/command.py
    for command in sub.choices.values():
        _add_logging_options(command)
    return parser


LOG_LEVELS = ("debug", "info", "warning", "error")


def _add_logging_options(parser: argparse.ArgumentParser) -> None:
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


def _configure_logging(args: argparse.Namespace) -> None:
    """With ``-v`` or ``--log-level`` the program shows the package's log lines of that level on
    stderr; without them logging is left as it is (Python shows warnings and errors)."""
    import logging

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


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    func: Callable[[argparse.Namespace], int] = args.func
    _configure_logging(args)
    try:
        return func(args)
    except SdarError as error:
        print(f"sdar: error: {error}", file=sys.stderr)
        return 2
    except OSError as error:  # a file that could not be read or written after the checks
        where = f"{error.filename}: " if error.filename else ""
        print(f"sdar: error: {where}{error.strerror or error}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
