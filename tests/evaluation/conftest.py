"""Benchmark folders with finished rows, so that a run finds nothing left to solve."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import pytest

from sdar_tamp.evaluation.results import (
    COLUMNS,
    COMBINATIONS,
    RESULTS,
    STEP_COLUMNS,
    STEPS,
    append_rows,
)

FinishedFolder = Callable[..., Path]


def _row(instance: str, combo: str, seed: int, time_limit: float) -> dict[str, Any]:
    c = next(c for c in COMBINATIONS if c.id == combo)
    return dict(
        instance=instance, family=instance[0], objects=int(instance[1:]), combination=combo,
        task_planner=c.task_planner, motion_planner=c.motion_planner, seed=seed,
        time_limit_s=time_limit, success=True, status="solved", valid=True, actions=4, steps=2,
        dual_arm_steps=1, execution_time_s=10.0, planning_time_s=1.0, abstract_actions=4,
        abstract_buffer_moves=0, abstract_steps=2,
    )  # fmt: skip


@pytest.fixture
def finished_folder() -> FinishedFolder:
    """``make(folder, pairs, seed=0, time_limit=60.0)``: ``results.csv`` with a solved row
    and ``steps.csv`` with two steps for each (instance, combination) pair."""

    def make(
        folder: Path, pairs: Sequence[tuple[str, str]], seed: int = 0, time_limit: float = 60.0
    ) -> Path:
        folder.mkdir(parents=True, exist_ok=True)
        rows = [_row(i, c, seed, time_limit) for i, c in pairs]
        steps = [
            dict(instance=i, combination=c, step=k, selection_s=0.1, motion_s=0.2)
            for i, c in pairs for k in range(2)
        ]  # fmt: skip
        append_rows(folder / STEPS, STEP_COLUMNS, steps)
        append_rows(folder / RESULTS, COLUMNS, rows)
        return folder

    return make
