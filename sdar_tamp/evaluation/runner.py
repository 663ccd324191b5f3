"""Run every (instance, planner combination) of a suite in worker processes, one CSV row each.

Output folder:

- ``results.csv``: one row per finished run (:data:`COLUMNS`), appended and flushed as soon
  as the run ends, whole lines only. A rerun skips every (instance, combination) pair already
  in the file, so an interrupted benchmark resumes where it stopped (delete a row to run that
  pair again).
- ``steps.csv``: planning time [s] of every synchronous step of every solved run, split into
  plan selection (IK, grasps, buffers, ranking) and motion generation (:data:`STEP_COLUMNS`).
- ``plans/INSTANCE__COMBINATION.json``: the plan file of every run that produced a plan
  (:mod:`sdar_tamp.plan_file`; ``sdar validate`` and ``sdar show`` read it), written before
  its row.
- ``settings.json``: what the rows depend on (seed, time limit, workers, backend, shard,
  suite, instance file hashes, version; :mod:`sdar_tamp.evaluation.settings`). A rerun with
  other settings is refused instead of mixing their rows; ``restart=True`` discards the old
  rows.

Each run is solved by a backend (:mod:`sdar_tamp.evaluation.backends`): a worker process on
this machine (:class:`~sdar_tamp.evaluation.workers.WorkerPool`), or a Ray task on a cluster
(:mod:`sdar_tamp.evaluation.ray_backend`) that carries the instance as text
(:mod:`sdar_tamp.evaluation.payload`). Only this process writes the folder. A run that
overruns a hard limit (by default ``2 * time_limit + 120`` s: set-up, abstract run and replay
come on top of the time limit) is killed and recorded as a ``timeout`` row, one whose worker
crashes as an ``error`` row, and no worker outlives the benchmark, even if it is killed.
``shard`` (:mod:`sdar_tamp.evaluation.shards`) keeps one of N disjoint parts of the pairs.

A run succeeds when it is solved *and* its plan passes the independent replay. Each row also
holds the task planner's geometry-free action count (:mod:`sdar_tamp.app.abstract`), which
compares SDAR-T with the baseline independently of motion failures. Every worker process
keeps one :class:`~sdar_tamp.app.cache.PlannerCache`, so it builds the motion planner once.
Parallel runs share the cores: compare planning times only between runs made with the same
``workers``.
"""

from __future__ import annotations

import argparse
import functools
import logging
import os
import re
import shlex
import shutil
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING, Any

from sdar_tamp import __version__
from sdar_tamp.arguments import COUNT, SEED, TIME_LIMIT
from sdar_tamp.errors import ParameterError, SdarError
from sdar_tamp.evaluation.backends import check_backend, open_backend
from sdar_tamp.evaluation.payload import InstanceFiles, pack, unpack
from sdar_tamp.evaluation.results import (
    COLUMNS,
    COMBINATIONS,
    PLANS,
    RESULTS,
    STEP_COLUMNS,
    STEPS,
    Combination,
    append_rows,
    instance_sort_key,
    load_results,
    parse_combos,
    plan_path,
    read_rows,
)
from sdar_tamp.evaluation.settings import (
    SETTINGS,
    BenchSettings,
    file_digest,
    plan_extras,
    read_settings,
    reconcile,
    write_settings,
)
from sdar_tamp.evaluation.shards import Shard, parse_shard
from sdar_tamp.evaluation.workers import WorkerFailure
from sdar_tamp.textfile import read_text

if TYPE_CHECKING:
    from sdar_tamp.app.cache import PlannerCache
    from sdar_tamp.plan_file import PlanFile

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class SuiteEntry:
    """One instance file of a suite."""

    path: Path
    name: str
    family: str
    objects: int


def suite_entries(
    suite: str | Path, only: Sequence[str] | None = None, max_objects: int | None = None
) -> list[SuiteEntry]:
    """The instances of ``suite`` (a shipped suite name or a folder of instance YAML files),
    keeping the names in ``only`` (instance or file names) and at most ``max_objects``."""
    from sdar_tamp.world.instance import load_instance

    folder, _ = suite_folder(suite)
    entries = []
    for path in sorted(folder.glob("*.yaml")):
        inst = load_instance(path)
        family = inst.family or re.sub(r"\d.*", "", inst.name)
        entries.append(SuiteEntry(path, inst.name, family, len(inst.objects)))
    names_seen = [e.name for e in entries]
    if len(set(names_seen)) < len(names_seen):
        raise SdarError(f"{folder}: two instance files share an instance name")
    if only:
        known = {e.name for e in entries} | {e.path.stem for e in entries}
        missing = [n for n in only if n not in known]
        if missing:
            raise ParameterError(f"only: no instance {', '.join(missing)} in {folder}")
        entries = [e for e in entries if e.name in only or e.path.stem in only]
    if max_objects is not None:
        entries = [e for e in entries if e.objects <= max_objects]
    if not entries:
        raise ParameterError(f"no instance of {folder} is selected")
    return sorted(entries, key=lambda e: (e.objects, instance_sort_key(e.name)))


def suite_folder(suite: str | Path) -> tuple[Path, bool]:
    """The folder of ``suite`` and whether it is a shipped suite.

    A :class:`Path`, or a string with a path separator (``./paper``, ``/data/tables``), is a
    folder. A bare name is the shipped suite of that name; a folder of that name in the
    working directory is used only when no suite is shipped under it. A bare name that is
    both a shipped suite and a folder of instance files here is refused as ambiguous (write
    ``./name`` for the folder); a folder of that name without instance files (an earlier
    ``--out``, say) does not hide the shipped suite."""
    from sdar_tamp.resources import domain_file

    shipped_root = domain_file("dual_arm_rearrangement").parent / "suites"
    shipped = sorted(p.name for p in shipped_root.iterdir() if p.is_dir() and p.name[0] != "_")
    text = str(suite)
    bare = isinstance(suite, str) and "/" not in text and os.sep not in text
    local = Path(text)
    if bare and text in shipped:
        if local.is_dir() and any(local.glob("*.yaml")):
            raise ParameterError(
                f"suite {text!r} is both a shipped suite and a folder of instances here; "
                f"write ./{text} for the folder, or run from another directory for the "
                "shipped suite"
            )
        return shipped_root / text, True
    if local.is_dir():
        return local, False
    raise ParameterError(f"suite must be a folder or one of {', '.join(shipped)}; got {text!r}")


def suite_label(suite: str | Path) -> str:
    """How the settings record names ``suite``: a folder by its resolved path, a shipped
    suite by its name."""
    folder, shipped = suite_folder(suite)
    return str(suite) if shipped else str(folder.resolve())


@dataclass(frozen=True)
class _Task:
    entry: SuiteEntry
    combo: Combination
    time_limit: float
    seed: int
    files: InstanceFiles | None = None  # the instance as text, for a machine without the suite


Answer = tuple[dict[str, Any], list[tuple[float, float]], "PlanFile | None"]


@functools.cache
def _worker_cache() -> PlannerCache:
    """Per worker process: the world and motion planner kept between runs."""
    from sdar_tamp.app.cache import PlannerCache

    return PlannerCache()


@functools.cache
def _abstract_figures(path: Path, task_planner: str) -> dict[str, int | None]:
    """The task planner's geometry-free counts, once per worker, instance and planner."""
    from sdar_tamp.app.abstract import abstract_figures

    run = abstract_figures(path, task_planner)
    return {
        "abstract_actions": run.actions,
        "abstract_buffer_moves": run.buffer_moves,
        "abstract_steps": run.steps,
    }


def _task_row(task: _Task) -> dict[str, Any]:
    """The columns of a row known before the run."""
    e, c = task.entry, task.combo
    return dict(
        instance=e.name, family=e.family, objects=e.objects, combination=c.id,
        task_planner=c.task_planner, motion_planner=c.motion_planner, seed=task.seed,
        time_limit_s=task.time_limit,
    )  # fmt: skip


def _run_task(task: _Task) -> Answer:
    """One solve in a worker: the CSV row, the per-step planning times and the plan."""
    from sdar_tamp.app.pipeline import solve_instance

    e, c = task.entry, task.combo
    path = e.path if task.files is None else unpack(task.files)
    row = _task_row(task)
    row.update(_abstract_figures(path, c.task_planner))
    start = time.perf_counter()
    try:
        outcome = solve_instance(
            path, time_limit=task.time_limit, seed=task.seed, task_planner=c.task_planner,
            motion_planner=c.motion_planner, execution=c.execution, cache=_worker_cache(),
        )  # fmt: skip
    except Exception as error:  # one broken run is recorded as such, not the end of the bench
        log.exception("%s with %s raised", e.name, c.id)
        row.update(status="error", success=False, valid=False, diagnosis=repr(error))
        row["wall_time_s"] = time.perf_counter() - start
        return row, [], None
    f = outcome.figures
    row.update(
        status=outcome.status, success=outcome.success, valid=outcome.valid,
        violation=outcome.violation, diagnosis=outcome.diagnosis[0] if outcome.diagnosis else "",
        planning_time_s=f.planning_time, selection_time_s=f.selection_time,
        motion_time_s=f.motion_time, setup_time_s=f.setup_time,
        wall_time_s=time.perf_counter() - start,
    )  # fmt: skip
    if outcome.plan is None:
        return row, [], None
    m = outcome.plan.metrics
    row.update(
        actions=m["actions"], steps=m["steps"], dual_arm_steps=m["dual_arm_steps"],
        execution_time_s=m["execution_time"], buffer_moves=f.buffer_moves,
        step_time_median_s=f.step_time_median,
    )  # fmt: skip
    return row, [(step.selection, step.motion) for step in f.step_times], outcome.plan


def finished_pairs(out_dir: Path) -> set[tuple[str, str]]:
    """(instance, combination) pairs already in ``results.csv``; repairs both files after an
    interruption (a cut-short last row, steps of a run whose row was never written)."""
    out = Path(out_dir)
    results = _repaired(out / RESULTS, COLUMNS, lambda r: True)
    done = {(r["instance"], r["combination"]) for r in results}
    _repaired(out / STEPS, STEP_COLUMNS, lambda r: (r["instance"], r["combination"]) in done)
    return done


def _repaired(
    path: Path, columns: Sequence[str], keep: Callable[[dict[str, str]], bool]
) -> list[dict[str, str]]:
    """The complete rows of ``path`` that ``keep`` accepts; the file is rewritten with only
    those if it holds anything else."""
    rows = read_rows(path, columns)
    kept = [r for r in rows if keep(r)]
    text = read_text(path) if path.exists() else "\n"
    if not text.endswith("\n") or text.count("\n") != len(kept) + 1:
        path.unlink(missing_ok=True)
        append_rows(path, columns, kept)
    return kept


def default_hard_limit(time_limit: float) -> float:
    """[s] a worker may spend on one run before it is killed: the planner's ``time_limit``
    plus set-up (the motion planner, built once per worker), abstract run and replay."""
    return 2.0 * time_limit + 120.0


def run_bench(
    suite: str | Path,
    out_dir: str | Path,
    combos: str | Sequence[str] = "all",
    *,
    workers: int | None = None,
    time_limit: float = 60.0,
    instances: Sequence[str] | None = None,
    max_objects: int | None = None,
    seed: int = 0,
    progress: bool = True,
    restart: bool = False,
    hard_limit: float | None = None,
    backend: str = "process",
    address: str | None = None,
    shard: Shard | str | None = None,
) -> Path:
    """Solve every (instance, combination) of ``suite`` not yet in ``out_dir/results.csv``
    with ``time_limit`` [s] per run; returns the results file.

    ``backend``: ``process`` (``workers`` processes here, default 1) or ``ray`` (at most
    ``workers`` Ray tasks at once, default one per cluster CPU; ``address``: the cluster,
    default ``$RAY_ADDRESS`` or a local Ray). ``shard`` (``"i/N"`` or a :class:`Shard`):
    only the pairs of that shard. Rows already in the folder are reused only if they were
    made with the same settings (:mod:`sdar_tamp.evaluation.settings`); otherwise
    :class:`SettingsMismatch` is raised before anything runs, unless ``restart`` discards
    them first. ``hard_limit`` [s] (default :func:`default_hard_limit`) bounds one run. An
    exception (``KeyboardInterrupt``) kills the runs in progress and leaves every finished
    row in place."""
    from tqdm import tqdm

    chosen = parse_combos(combos)
    backend = check_backend(backend, address)
    if workers is not None:
        workers = COUNT.check("workers", workers)
    time_limit = TIME_LIMIT.check("time_limit", time_limit)
    seed = SEED.check("seed", seed)
    if max_objects is not None:
        max_objects = COUNT.check("max_objects", max_objects)
    if hard_limit is None:
        hard_limit = default_hard_limit(time_limit)
    hard_limit = TIME_LIMIT.check("hard_limit", hard_limit)
    if isinstance(shard, str):
        shard = parse_shard(shard)
    entries = suite_entries(suite, instances, max_objects)
    runs = open_backend(backend, _run_task, workers, hard_limit=hard_limit, address=address)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if restart:
        for name in (RESULTS, STEPS, SETTINGS):
            (out / name).unlink(missing_ok=True)
        shutil.rmtree(out / PLANS, ignore_errors=True)
    recorded_workers = workers if workers is not None else (1 if backend == "process" else 0)
    wanted = BenchSettings(
        version=__version__, suite=suite_label(suite), seed=seed, time_limit_s=time_limit,
        workers=recorded_workers, instances={e.name: file_digest(e.path) for e in entries},
        backend=backend, shard=str(shard) if shard is not None else "",
        extras=plan_extras(),
    )  # fmt: skip
    write_settings(out, reconcile(out, wanted, load_results(out)))
    done = finished_pairs(out)
    pending = [
        (e, c)
        for e in entries
        for c in chosen
        if (e.name, c.id) not in done and (shard is None or shard.takes(e.name, c.id))
    ]
    carried: dict[str, InstanceFiles] = {}  # the instances as text, for Ray nodes
    for e, _ in pending if backend == "ray" else []:
        if e.name not in carried:
            carried[e.name] = pack(e.path)
    tasks = [_Task(e, c, time_limit, seed, carried.get(e.name)) for e, c in pending]
    if not tasks:
        return out / RESULTS
    bar = tqdm(total=len(tasks), desc="bench", unit="run", file=sys.stderr, disable=not progress)
    try:
        with runs:
            for task, answer in runs.run(tasks):
                row = _record(out, task, answer)
                if row is None:
                    continue
                bar.set_postfix_str(f"{row['instance']} {row['combination']}: {row['status']}")
                bar.update(1)
    finally:
        bar.close()
    return out / RESULTS


def _record(out: Path, task: _Task, answer: Answer | WorkerFailure) -> dict[str, Any] | None:
    """Write a run's plan, steps and row (in this order: see :func:`finished_pairs`); returns
    the row, ``None`` for a run not to record."""
    steps: list[tuple[float, float]] = []
    if isinstance(answer, WorkerFailure):
        row = _failed_row(task, answer)
        if row is None:
            return None
    else:
        row, steps, plan = answer
        if plan is not None:
            from sdar_tamp.plan_file import save_plan

            save_plan(plan, plan_path(out, row["instance"], row["combination"]))
    step_rows = [
        dict(instance=row["instance"], combination=row["combination"], step=i, selection_s=s,
             motion_s=m)
        for i, (s, m) in enumerate(steps)
    ]  # fmt: skip
    append_rows(out / STEPS, STEP_COLUMNS, step_rows)
    append_rows(out / RESULTS, COLUMNS, [row])
    return row


def _failed_row(task: _Task, failure: WorkerFailure) -> dict[str, Any] | None:
    """The row of a run without an answer: ``timeout`` when it overran the hard limit, else
    ``error``; ``None`` (no row: a rerun runs it again) when its worker was terminated from
    outside."""
    name = f"{task.entry.name} with {task.combo.id}"
    if failure.external:
        log.warning("%s not recorded: %s", name, failure.reason)
        return None
    log.error("%s: %s", name, failure.reason)
    row = _task_row(task)
    status = "timeout" if failure.timed_out else "error"
    row.update(status=status, success=False, valid=False, diagnosis=failure.reason)
    return row


def bench_commands(
    out: str | Path, settings: BenchSettings, rows: Sequence[Mapping[str, str]],
    suite_names: Iterable[str],
) -> list[str]:  # fmt: skip
    """The ``sdar bench`` commands that made ``rows`` under ``settings`` (rerun: resumes, then
    redraws): one per group of instances run with the same combinations; for a shard, one
    command (a shard holds some combinations of each instance)."""
    if settings.shard:
        return [_shard_command(out, settings, rows, suite_names)]
    by_instance: dict[str, set[str]] = {}
    objects: dict[str, int] = {}
    for r in rows:
        by_instance.setdefault(r["instance"], set()).add(r["combination"])
        objects[r["instance"]] = int(r["objects"]) if r["objects"].isdigit() else 0
    groups: dict[frozenset[str], list[str]] = {}
    for name in sorted(by_instance, key=lambda n: (objects[n], instance_sort_key(n))):
        groups.setdefault(frozenset(by_instance[name]), []).append(name)
    base = _base_command(out, settings)
    everything = set(suite_names)
    commands = []
    for combos, names in groups.items():
        command = f"{base[0]} --combos {shlex.quote(_combo_arg(set(combos)))} {base[1]}"
        if len(groups) > 1 or set(names) != everything:
            command += f" --only {shlex.quote(','.join(names))}"
        commands.append(command)
    return commands


def _base_command(out: str | Path, settings: BenchSettings) -> tuple[str, str]:
    workers = f"--workers {settings.workers} " if settings.workers else ""
    where = " --backend ray" if settings.backend == "ray" else ""
    where += f" --shard {settings.shard}" if settings.shard else ""
    return (
        f"sdar bench --suite {shlex.quote(settings.suite)} --out {shlex.quote(str(out))}",
        f"{workers}--time-limit {_number(settings.time_limit_s)} --seed {settings.seed}{where}",
    )


def _combo_arg(combos: set[str]) -> str:
    ids = [c.id for c in COMBINATIONS if c.id in combos]
    ids += sorted(combos - set(ids))  # ids of another version, kept as they are
    return "all" if ids == [c.id for c in COMBINATIONS] else ",".join(ids)


def _shard_command(
    out: str | Path, settings: BenchSettings, rows: Sequence[Mapping[str, str]],
    suite_names: Iterable[str],
) -> str:  # fmt: skip
    head, tail = _base_command(out, settings)
    command = f"{head} --combos {shlex.quote(_combo_arg({r['combination'] for r in rows}))} {tail}"
    selected = set(settings.instances)
    if selected != set(suite_names):
        names = sorted(selected, key=instance_sort_key)
        command += f" --only {shlex.quote(','.join(names))}"
    return command


def _number(value: float) -> str:
    short = f"{value:g}"
    return short if float(short) == value else repr(value)


class BenchInterrupted(KeyboardInterrupt):
    """``sdar bench`` stopped by a signal (SIGINT or SIGTERM)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def _interrupt(signum: int, frame: FrameType | None) -> None:
    for name in ("SIGINT", "SIGTERM"):  # a second signal must not break the clean-up
        signal.signal(getattr(signal, name), signal.SIG_IGN)
    raise BenchInterrupted(signum)


def bench_command(args: argparse.Namespace) -> int:
    """``sdar bench``: run (or resume) the benchmark, then write the plots and the report.

    SIGINT (Ctrl-C) and SIGTERM stop it with one line on stderr and exit status 128 + the
    signal number (130, 143); the workers are killed and the finished rows stay."""
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
            backend=args.backend, address=args.address, shard=args.shard,
        )  # fmt: skip
    print(f"results: {results}")
    return _redraw(results.parent, args.out)


def _suite_names(settings: BenchSettings) -> list[str]:
    """The instance names of the recorded suite; those of the record when the suite is not
    on this machine (a merged folder of a sweep made elsewhere)."""
    try:
        return [e.name for e in suite_entries(settings.suite)]
    except SdarError:
        return list(settings.instances)


def _redraw(folder: Path, out: str | Path) -> int:
    """Plots and report of a benchmark folder; prints the success table."""
    from sdar_tamp.evaluation.report import success_lines, write_report

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
