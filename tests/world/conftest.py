from __future__ import annotations

import pytest

from sdar_tamp.world.scene import Scene, load_scene


@pytest.fixture(scope="session")
def scene() -> Scene:
    return load_scene()
