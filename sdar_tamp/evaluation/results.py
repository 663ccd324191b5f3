"""The results of a benchmark folder: planner combinations and the CSV files' rows.

``results.csv`` holds one row per finished run (:data:`COLUMNS`), ``steps.csv`` the planning
time [s] of every synchronous step (:data:`STEP_COLUMNS`). The runner writes them; the report
and the plots read them. This module imports nothing of the planners.
"""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from sdar_tamp.errors import ParameterError, SdarError
from sdar_tamp.textfile import read_text

Row = dict[str, str]

RESULTS = "results.csv"
STEPS = "steps.csv"
PLANS = "plans"
COLUMNS = (
    "instance", "family", "objects", "combination", "task_planner", "motion_planner", "seed",
    "time_limit_s", "success", "status", "valid", "actions", "steps", "dual_arm_steps",
    "buffer_moves", "execution_time_s", "bound_s", "execution_over_bound", "planning_time_s",
    "selection_time_s", "motion_time_s", "step_time_median_s", "setup_time_s", "wall_time_s",
    "abstract_actions", "abstract_buffer_moves", "abstract_steps", "violation", "diagnosis",
)  # fmt: skip
STEP_COLUMNS = ("instance", "combination", "step", "selection_s", "motion_s")
FAMILY_ORDER = "RSDMN"


@dataclass(frozen=True)
class Combination:
    """A task planner paired with a motion planner and an execution (the paper's six, all
    synchronous, and SDAR executed asynchronously: :data:`COMBINATIONS`)."""

    id: str
    label: str
    task_planner: str  # sdar | baseline
    motion_planner: str  # sdar | plain | sequential
    execution: str = "sync"  # sync | async


COMBINATIONS = (
    Combination("sdar", "SDAR", "sdar", "sdar"),
    Combination("baseline", "Baseline", "baseline", "sequential"),
    Combination("baseline-tp+sdar-m", "Baseline TP + SDAR-M", "baseline", "sdar"),
    Combination("sdar-t+baseline-mp", "SDAR-T + Baseline MP", "sdar", "sequential"),
    Combination("sdar-t+plain", "SDAR-T + plain TO", "sdar", "plain"),
    Combination("baseline-tp+plain", "Baseline TP + plain TO", "baseline", "plain"),
    Combination("sdar-async", "SDAR, asynchronous", "sdar", "sdar", "async"),
)


def parse_combos(spec: str | Sequence[str]) -> tuple[Combination, ...]:
    """``"all"`` or comma-separated ids (or a list of ids), returned in :data:`COMBINATIONS`
    order. Raises :class:`ParameterError` for an unknown, empty or repeated id."""
    names = [s.strip() for s in (spec.split(",") if isinstance(spec, str) else spec)]
    if names == ["all"]:
        return COMBINATIONS
    choices = f"'all' or a comma-separated list of {', '.join(c.id for c in COMBINATIONS)}"
    unknown = [n for n in names if n not in {c.id for c in COMBINATIONS}]
    if unknown:
        raise ParameterError(f"combos must be {choices}; unknown: {', '.join(map(repr, unknown))}")
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise ParameterError(f"combos: {', '.join(repeated)} given more than once")
    return tuple(c for c in COMBINATIONS if c.id in names)


def instance_sort_key(name: str) -> tuple[int, int, str]:
    """R, S, D, M (then others), by the number in the name: R4 < R10 < S4 < M1."""
    family = FAMILY_ORDER.find(name[:1]) if name[:1] else -1
    digits = re.search(r"\d+", name)
    return (
        family if family >= 0 else len(FAMILY_ORDER),
        int(digits.group()) if digits else 0,
        name,
    )


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return str(int(value))
    if isinstance(value, float):
        return f"{value:.6g}"
    return " ".join(str(value).split())  # one line per row, whatever a message holds


def append_rows(path: Path, columns: Sequence[str], rows: Iterable[Mapping[str, Any]]) -> None:
    """Append ``rows`` to the CSV file ``path`` (header first if new) and flush. The text is
    written in one call, so an interruption (``KeyboardInterrupt``) leaves whole lines."""
    new = not path.exists() or path.stat().st_size == 0
    text = io.StringIO()
    writer = csv.writer(text)
    if new:
        writer.writerow(columns)
    writer.writerows([_cell(r.get(c)) for c in columns] for r in rows)
    with path.open("a", newline="", encoding="utf-8") as fh:
        fh.write(text.getvalue())
        fh.flush()


def read_rows(path: Path, columns: Sequence[str]) -> list[dict[str, str]]:
    """The complete rows of a CSV file written by :func:`append_rows` (a last line cut short
    by an interruption is dropped). Raises :class:`SdarError` if the header is not ``columns``."""
    if not path.exists():
        return []
    text = read_text(path)
    lines = text.splitlines(keepends=True)
    if lines and not lines[-1].endswith("\n"):
        lines.pop()
    reader = csv.reader(lines)
    header = next(reader, None)
    if header is not None and tuple(header) != tuple(columns):
        raise SdarError(
            f"{path}: unexpected columns (written by another version?); use a new folder"
        )
    return [dict(zip(columns, r, strict=True)) for r in reader if len(r) == len(columns)]


def plan_path(out_dir: Path, instance: str, combination: str) -> Path:
    """Where a benchmark folder keeps the plan file of a run."""
    return Path(out_dir) / PLANS / f"{instance}__{combination}.json"


def load_results(out_dir: Path) -> list[dict[str, str]]:
    return read_rows(Path(out_dir) / RESULTS, COLUMNS)


def load_steps(out_dir: Path) -> list[dict[str, str]]:
    return read_rows(Path(out_dir) / STEPS, STEP_COLUMNS)
