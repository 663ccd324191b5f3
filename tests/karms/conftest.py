"""Fixtures of the k-arm test cells (one, three and four UR5e arms): see ``karm_cells.py``."""

from __future__ import annotations

import pytest
from karm_cells import build, cell, crossing, instance_of, pick_place

from sdar_tamp.plan_file import PlanFile
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.scene import Scene


@pytest.fixture(scope="session")
def cells() -> dict[int, Scene]:
    return {k: cell(k) for k in (1, 3, 4)}


@pytest.fixture(scope="session")
def instances(cells: dict[int, Scene]) -> dict[int, Instance]:
    return {k: instance_of(f"K{k}", scene, crossing(k)) for k, scene in cells.items()}


@pytest.fixture(scope="session")
def plans(cells: dict[int, Scene], instances: dict[int, Instance]) -> dict[int, PlanFile]:
    """Every arm of the cell carries its object towards the middle at once (the four-arm
    plan's grippers end up a few centimetres apart)."""
    return {
        k: build(scene, instances[k], pick_place(scene, crossing(k))) for k, scene in cells.items()
    }
