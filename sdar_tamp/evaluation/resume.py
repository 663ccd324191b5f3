"""Resuming a benchmark folder: the runs already finished, after repairing an interruption."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

from sdar_tamp.evaluation.results import (
    COLUMNS,
    RESULTS,
    STEP_COLUMNS,
    STEPS,
    append_rows,
    read_rows,
)
from sdar_tamp.textfile import read_text


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
