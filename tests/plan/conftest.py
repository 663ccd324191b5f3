"""Shared, expensive fixtures of the plan tests: the world context and the motion planner."""

from __future__ import annotations

import pytest

from streams.context import WorldContext
from streams.motion import DualMotionPlanner


@pytest.fixture(scope="session")
def world_ctx() -> WorldContext:
    return WorldContext.load()


@pytest.fixture(scope="session")
def motion_planner(world_ctx: WorldContext) -> DualMotionPlanner:
    return DualMotionPlanner(world_ctx)
