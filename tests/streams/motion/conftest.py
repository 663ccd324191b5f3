"""Fixtures of the motion tests with one to four arms: the test cells of ``data/``
(``table_1arm.yaml``, ``table_3arm.yaml``, ``table_4arm.yaml``; the two-arm cell is the shipped
one of tests/conftest.py) and an optimiser cache of their own."""

from __future__ import annotations

from pathlib import Path

import pytest

from streams.context import WorldContext
from streams.motion.optimiser_cache import OptimiserCache

DATA = Path(__file__).parent / "data"


@pytest.fixture(scope="module")
def cells() -> dict[int, WorldContext]:
    return {k: WorldContext.load(DATA / f"table_{k}arm.yaml") for k in (1, 3, 4)}


@pytest.fixture(scope="module")
def k_optimisers() -> OptimiserCache:
    return OptimiserCache()
