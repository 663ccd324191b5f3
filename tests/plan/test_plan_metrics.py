"""The plan's metrics record: named fields, the plan file's keys and order, other metrics kept."""

from __future__ import annotations

from sdar_tamp.plan_metrics import PlanMetrics


def test_known_keys_are_fields_and_the_json_lists_the_present_ones_in_field_order() -> None:
    m = PlanMetrics.from_mapping(
        {"execution_time": 7.8, "note": "x", "planning_time": 1.5, "seed": 3, "actions": 4}
    )
    assert (m.planning_time, m.seed, m.actions, m.execution_time) == (1.5, 3, 4, 7.8)
    assert m.extra == {"note": "x"} and m.steps is None
    assert list(m.as_json()) == ["planning_time", "seed", "actions", "execution_time", "note"]
    assert m.as_json()["note"] == "x" and "steps" not in m.as_json()


def test_a_value_of_another_type_stays_under_its_key() -> None:
    """Old plan files may hold any string or number under a known key: read, kept, written."""
    m = PlanMetrics.from_mapping({"seed": "abc", "actions": 2.5})
    assert m.seed is None and m.actions is None
    assert m.as_json() == {"seed": "abc", "actions": 2.5}


def test_updated_replaces_and_appends() -> None:
    m = PlanMetrics.from_mapping({"actions": 1, "execution_time": 2.0})
    u = m.updated({"execution": "async", "execution_time": 1.5, "execution_time_sync": 2.0})
    assert u.as_json() == {
        "actions": 1, "execution_time": 1.5, "execution": "async", "execution_time_sync": 2.0
    }  # fmt: skip
    assert m.execution_time == 2.0  # unchanged
