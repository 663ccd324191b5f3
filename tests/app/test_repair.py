"""The repair's planning budget (``sdar_tamp.app.repair``; the repair itself is tested through
re-planning, ``test_replanning.py``)."""

from __future__ import annotations

import pytest

from sdar_tamp.app.repair import repair_budget


@pytest.mark.parametrize(("limit", "budget"), [(60.0, 15.0), (30.0, 7.5), (8.0, 3.0), (2.0, 2.0)])
def test_the_repair_budget(limit: float, budget: float) -> None:
    """A quarter of the time limit, at least 3 s, never more than the limit."""
    assert repair_budget(limit) == pytest.approx(budget)
