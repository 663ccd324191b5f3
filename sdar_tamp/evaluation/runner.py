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

A run succeeds when it is solved *and* its plan passes the independent replay. Each row
(:class:`~sdar_tamp.evaluation.records.BenchRow`) also holds the task planner's geometry-free
action count (:mod:`sdar_tamp.app.abstract`), which compares SDAR-T with the baseline
independently of motion failures. A worker solves one run with
:func:`~sdar_tamp.evaluation.bench_task.run_task`; the suite's instances come from
:mod:`sdar_tamp.evaluation.suite`, the finished runs of a folder from
:mod:`sdar_tamp.evaluation.resume`. Parallel runs share the cores: compare planning times only
between runs made with the same ``workers``.
"""

from __future__ import annotations

import logging
import shutil
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from sdar_tamp import __version__
from sdar_tamp.arguments import COUNT, SEED, TIME_LIMIT
from sdar_tamp.errors import ParameterError
from sdar_tamp.evaluation.backends import check_backend, open_backend
from sdar_tamp.evaluation.bench_task import BenchTask, run_task, task_row
from sdar_tamp.evaluation.payload import InstanceFiles, pack
from sdar_tamp.evaluation.records import BenchRow, RunAnswer
from sdar_tamp.evaluation.results import (
    COLUMNS,
    PLANS,
    RESULTS,
    STEP_COLUMNS,
    STEPS,
    append_rows,
    load_results,
    parse_combos,
    plan_path,
)
from sdar_tamp.evaluation.resume import finished_pairs
from sdar_tamp.evaluation.settings import (
    SETTINGS,
    BenchSettings,
    file_digest,
    plan_extras,
    reconcile,
    write_settings,
)
from sdar_tamp.evaluation.shards import Shard, parse_shard
from sdar_tamp.evaluation.suite import suite_entries, suite_label
from sdar_tamp.evaluation.workers import WorkerFailure

if TYPE_CHECKING:
    from sdar_tamp.app.records import StepTime

log = logging.getLogger(__name__)


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
    scene: Path | None = None,
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
    row in place. ``scene``: a scene file (cell) replacing every instance's own (local
    processes only; recorded in the settings with its content's digest)."""
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
    scene_record = ""
    if scene is not None:
        if backend == "ray":
            raise ParameterError(
                "scene: a replacing scene file runs with the process backend only; with Ray, "
                "name the scene in the instance files (they travel with them)"
            )
        scene = Path(scene).resolve()
        scene_record = f"{scene} sha256:{file_digest(scene)}"
    entries = suite_entries(suite, instances, max_objects)
    runs = open_backend(backend, run_task, workers, hard_limit=hard_limit, address=address)
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
        extras=plan_extras(), scene=scene_record,
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
    tasks = [BenchTask(e, c, time_limit, seed, carried.get(e.name), scene) for e, c in pending]
    if not tasks:
        return out / RESULTS
    bar = tqdm(total=len(tasks), desc="bench", unit="run", file=sys.stderr, disable=not progress)
    try:
        with runs:
            for task, answer in runs.run(tasks):
                row = _record(out, task, answer)
                if row is None:
                    continue
                bar.set_postfix_str(f"{row.instance} {row.combination}: {row.status}")
                bar.update(1)
    finally:
        bar.close()
    return out / RESULTS


def _record(out: Path, task: BenchTask, answer: RunAnswer | WorkerFailure) -> BenchRow | None:
    """Write a run's plan, steps and row (in this order: see :func:`finished_pairs`); returns
    the row, ``None`` for a run not to record."""
    steps: tuple[StepTime, ...] = ()
    if isinstance(answer, WorkerFailure):
        failed = _failed_row(task, answer)
        if failed is None:
            return None
        row = failed
    else:
        row, steps = answer.row, answer.step_times
        if answer.plan is not None:
            from sdar_tamp.plan_writing import save_plan

            save_plan(answer.plan, plan_path(out, row.instance, row.combination))
    step_rows = [
        dict(instance=row.instance, combination=row.combination, step=i, selection_s=s,
             motion_s=m)
        for i, (s, m) in enumerate(steps)
    ]  # fmt: skip
    append_rows(out / STEPS, STEP_COLUMNS, step_rows)
    append_rows(out / RESULTS, COLUMNS, [row.cells()])
    return row


def _failed_row(task: BenchTask, failure: WorkerFailure) -> BenchRow | None:
    """The row of a run without an answer: ``timeout`` when it overran the hard limit, else
    ``error``; ``None`` (no row: a rerun runs it again) when its worker was terminated from
    outside."""
    name = f"{task.entry.name} with {task.combo.id}"
    if failure.external:
        log.warning("%s not recorded: %s", name, failure.reason)
        return None
    log.error("%s: %s", name, failure.reason)
    return task_row(task, "timeout" if failure.timed_out else "error", failure.reason)
