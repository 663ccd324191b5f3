"""Shipped suites for the benchmarks: their instance files in suite order, and a plan per
instance read from a folder of stored plans or solved (and stored)."""

from __future__ import annotations

import re
from pathlib import Path

from sdar_tamp.app import PlannerCache, PlannerConfig, solve_instance
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_writing import save_plan
from sdar_tamp.resources import domain_file


def suite_order(p: Path) -> tuple[str, int]:
    """An instance file's place in its suite: family letter, then the number in its name."""
    digits = re.sub(r"\D", "", p.stem)
    return (p.stem[0], int(digits) if digits else 0)


def shipped_suite_files(suite: str) -> list[Path]:
    """The instance files of the shipped ``suite``, in suite order.

    Raises:
        SystemExit: the suite is not shipped (it is generated in a cell).
    """
    folder = domain_file("dual_arm_rearrangement", "domain.pddl").parent / "suites" / suite
    if not folder.is_dir():
        raise SystemExit(
            f"--suite {suite}: not shipped; generate it in a cell (sdar generate --scene CELL "
            f"--suite {suite} -o DIR) and pass --folder DIR"
        )
    return sorted(folder.glob("*.yaml"), key=suite_order)


def stored_or_solved(
    path: Path,
    plans: Path | None,
    config: PlannerConfig,
    cache: PlannerCache,
    *,
    save: bool,
    refresh: bool,
) -> PlanFile | None:
    """The plan of the instance ``path``: ``plans/<name>.json`` where it exists (unless
    ``refresh``), else solved with ``config`` (None when that fails) and, with ``save`` and a
    ``plans`` folder, written there."""
    stored = plans / f"{path.stem}.json" if plans is not None else None
    if stored is not None and stored.exists() and not refresh:
        return load_plan(stored)
    outcome = solve_instance(path, config, cache=cache)
    if not outcome.success or outcome.plan is None:
        return None
    if stored is not None and save:
        save_plan(outcome.plan, stored)
    return outcome.plan
