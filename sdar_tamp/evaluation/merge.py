"""Join benchmark folders (the shards of a sweep) into one: ``sdar bench --merge A B ... --out C``.

The folders must have been made with the same settings but the shard (version, suite, seed,
time limit, workers, backend, and the same content for an instance they share); a pair
present in two folders is an error. The merged folder holds every row, step and plan of the
sources and a record without a shard, so ``sdar bench`` without ``--shard`` on it resumes: it
runs the pairs that no source finished. The sources are only read.
"""

from __future__ import annotations

import shutil
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

from sdar_tamp.errors import ParameterError, SdarError
from sdar_tamp.evaluation.results import (
    COLUMNS,
    RESULTS,
    STEP_COLUMNS,
    STEPS,
    append_rows,
    load_results,
    load_steps,
    plan_path,
)
from sdar_tamp.evaluation.settings import (
    SETTINGS,
    BenchSettings,
    SettingsMismatch,
    differences,
    read_settings,
    write_settings,
)


def _source_settings(folder: Path) -> BenchSettings:
    if not folder.is_dir():
        raise ParameterError(f"merge: {folder} is not a folder")
    settings = read_settings(folder)
    if settings is None:
        raise SdarError(f"merge: {folder} holds no {SETTINGS}; not a folder of `sdar bench`")
    return settings


def merge_folders(sources: Sequence[Path], out: Path) -> Path:
    """Write the rows, steps and plans of ``sources`` into ``out`` (a new folder, or one
    without results); returns ``out/results.csv``."""
    if not sources:
        raise ParameterError("merge: expected one or more folders")
    folders = [Path(s) for s in sources]
    out = Path(out)
    if out.resolve() in {f.resolve() for f in folders}:
        raise ParameterError(f"merge: --out {out} is one of the folders to merge; use a new one")
    if out.is_dir() and load_results(out):
        raise ParameterError(f"merge: {out} already holds results; merge into a new folder")
    records = [_source_settings(f) for f in folders]
    first = records[0]
    for folder, record in zip(folders[1:], records[1:], strict=True):
        found = differences(first, record, shard=False)
        if found:
            raise SettingsMismatch(
                f"merge: {folder} was made with other settings than {folders[0]}: "
                f"{'; '.join(found)}"
            )
    owner: dict[tuple[str, str], Path] = {}
    rows, steps = [], []
    for folder in folders:
        mine = load_results(folder)
        for r in mine:
            pair = (r["instance"], r["combination"])
            if pair in owner:
                raise SdarError(
                    f"merge: {pair[0]} with {pair[1]} is in both {owner[pair]} and {folder}"
                )
            owner[pair] = folder
        pairs = {(r["instance"], r["combination"]) for r in mine}
        steps += [s for s in load_steps(folder) if (s["instance"], s["combination"]) in pairs]
        rows += mine
    out.mkdir(parents=True, exist_ok=True)
    for (instance, combination), folder in owner.items():
        plan = plan_path(folder, instance, combination)
        if plan.is_file():
            target = plan_path(out, instance, combination)
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(plan, target)
    instances: dict[str, str] = {}
    for record in records:
        instances.update(record.instances)
    write_settings(out, replace(first, shard="", instances=instances))
    (out / STEPS).unlink(missing_ok=True)
    append_rows(out / STEPS, STEP_COLUMNS, steps)
    append_rows(out / RESULTS, COLUMNS, rows)
    return out / RESULTS
