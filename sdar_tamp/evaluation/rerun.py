"""The ``sdar bench`` commands that made a benchmark folder's rows (the report prints them:
rerunning one resumes, then redraws)."""

from __future__ import annotations

import shlex
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path

from sdar_tamp.evaluation.results import COMBINATIONS, instance_sort_key
from sdar_tamp.evaluation.settings import BenchSettings


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
