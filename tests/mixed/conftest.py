"""Fixtures of the mixed cell (a 6-joint and a 7-joint arm): see ``mixed_cell.py``."""

from __future__ import annotations

import pytest
from mixed_cell import OBJECTS, mixed_cell, mixed_plan

from sdar_tamp.plan_file import PlanFile
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.scene import Scene


@pytest.fixture(scope="session")
def cell() -> Scene:
    return mixed_cell()


@pytest.fixture(scope="session")
def plan(cell: Scene) -> PlanFile:
    return mixed_plan(cell)


@pytest.fixture(scope="session")
def instance(cell: Scene) -> Instance:
    return Instance("X2", cell.workspace, OBJECTS)
