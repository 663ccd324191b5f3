"""The plan's metrics record: named fields, the plan file's keys and order, other metrics kept."""

from __future__ import annotations

import pytest

from sdar_tamp.plan_metrics import PlanMetrics


def test_known_keys_are_fields_and_the_mapping_keeps_the_file_order() -> None:
    m = PlanMetrics.from_mapping(
        {"planning_time": 1.5, "seed": 3, "actions": 4, "execution_time": 7.8, "note": "x"}
    )
    assert (m.planning_time, m.seed, m.actions, m.execution_time) == (1.5, 3, 4, 7.8)
    assert m.extra == {"note": "x"} and m["note"] == "x" and m["actions"] == 4
    assert list(m) == ["planning_time", "seed", "actions", "execution_time", "note"]
    assert "steps" not in m and m.get("steps") is None
    with pytest.raises(KeyError):
        m["steps"]


def test_a_value_of_another_type_stays_under_its_key() -> None:
    """Old plan files may hold any string or number under a known key: read, kept, written."""
    m = PlanMetrics.from_mapping({"seed": "abc", "actions": 2.5})
    assert m.seed is None and m.actions is None
    assert dict(m) == {"seed": "abc", "actions": 2.5}


def test_updated_replaces_and_appends() -> None:
    m = PlanMetrics.from_mapping({"actions": 1, "execution_time": 2.0})
    u = m.updated({"execution": "async", "execution_time": 1.5, "execution_time_sync": 2.0})
    assert dict(u) == {
        "actions": 1, "execution_time": 1.5, "execution": "async", "execution_time_sync": 2.0
    }  # fmt: skip
    assert m.execution_time == 2.0  # unchanged
