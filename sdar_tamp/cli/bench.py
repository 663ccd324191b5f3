"""``sdar bench``: run (or resume, or merge) a benchmark, then write its plots and report.

SIGINT (Ctrl-C) and SIGTERM stop it with one line on stderr and exit status 128 + the signal
number (130, 143); the workers are killed and the finished rows stay.
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading
from collections.abc import Sequence
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING, Any

from sdar_tamp.arguments import COUNT, SEED, TIME_LIMIT
from sdar_tamp.cli.log_options import SCENE_HELP
from sdar_tamp.errors import SdarError

if TYPE_CHECKING:
    from sdar_tamp.evaluation.settings import BenchSettings


class BenchInterrupted(KeyboardInterrupt):
    """``sdar bench`` stopped by a signal (SIGINT or SIGTERM)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def _interrupt(signum: int, frame: FrameType | None) -> None:
    for name in ("SIGINT", "SIGTERM"):  # a second signal must not break the clean-up
        signal.signal(getattr(signal, name), signal.SIG_IGN)
    raise BenchInterrupted(signum)


def cmd_bench(args: argparse.Namespace) -> int:
    """Run the paper's evaluation: every planner combination on every instance of a suite, in
    worker processes. One CSV row per finished run, then plots and a report in the output
    folder. A rerun with the same settings resumes (Ctrl-C keeps the finished runs); one with
    another seed, time limit, worker count or suite is refused unless --restart is given."""
    from sdar_tamp.evaluation.results import RESULTS, load_results

    handled: tuple[signal.Signals, ...] = (signal.SIGINT, signal.SIGTERM)
    if threading.current_thread() is not threading.main_thread():
        handled = ()  # only the main thread may set handlers: plain KeyboardInterrupt then
    previous = {s: signal.getsignal(s) for s in handled}
    for s in handled:
        signal.signal(s, _interrupt)
    try:
        return _bench(args)
    except KeyboardInterrupt as stop:
        signum = stop.signum if isinstance(stop, BenchInterrupted) else signal.SIGINT
        results = Path(args.out) / RESULTS
        try:
            kept = f"{len(load_results(args.out))} finished runs kept in {results}"
        except (OSError, SdarError):
            kept = f"the finished runs stay in {results}"
        print(
            f"sdar bench: interrupted ({signal.Signals(signum).name}); {kept}; "
            "run the same command again to resume",
            file=sys.stderr,
        )
        return 128 + signum
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


def _bench(args: argparse.Namespace) -> int:
    from sdar_tamp.evaluation.runner import run_bench

    merge: Sequence[Path] | None = args.merge
    if merge:
        from sdar_tamp.evaluation.merge import merge_folders

        results = merge_folders(merge, args.out)
    else:
        only = [s.strip() for s in args.only.split(",") if s.strip()] if args.only else None
        results = run_bench(
            args.suite, args.out, args.combos, workers=args.workers, time_limit=args.time_limit,
            instances=only, max_objects=args.max_objects, seed=args.seed,
            progress=not args.quiet, restart=args.restart,
            backend=args.backend, address=args.address, shard=args.shard, scene=args.scene,
        )  # fmt: skip
    print(f"results: {results}")
    return _redraw(results.parent, args.out)


def _suite_names(settings: BenchSettings) -> list[str]:
    """The instance names of the recorded suite; those of the record when the suite is not
    on this machine (a merged folder of a sweep made elsewhere)."""
    from sdar_tamp.evaluation.suite import suite_entries

    try:
        return [e.name for e in suite_entries(settings.suite)]
    except SdarError:
        return list(settings.instances)


def _redraw(folder: Path, out: str | Path) -> int:
    """Plots and report of a benchmark folder; prints the success table."""
    from sdar_tamp.evaluation.report import success_lines, write_report
    from sdar_tamp.evaluation.rerun import bench_commands
    from sdar_tamp.evaluation.results import load_results
    from sdar_tamp.evaluation.settings import read_settings

    try:
        from sdar_tamp.evaluation.plots import write_plots
    except ImportError as error:  # matplotlib is an optional dependency (extra "viz")
        print(f"no plots: {error} (pip install 'sdar-tamp[viz]')", file=sys.stderr)
    else:
        print(f"plots: {', '.join(p.name for p in write_plots(folder))}")
    rows = load_results(folder)
    settings = read_settings(folder)
    commands: list[str] = []
    if settings is not None and rows:
        commands = bench_commands(out, settings, rows, _suite_names(settings))
    version = settings.version if settings is not None else None
    print(f"report: {write_report(folder, commands, version)}")
    print("\n".join(success_lines(rows)))
    return 0


def add_bench_parser(sub: argparse._SubParsersAction[Any]) -> None:
    """Register ``sdar bench``."""
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
    bench.add_argument("--scene", type=Path, default=None, help=SCENE_HELP)
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
