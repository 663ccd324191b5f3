"""The CSV export: a uniform 50 Hz grid over the whole plan, positions linear between the
plan's samples, gripper columns switching at the events."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.export import csv_header, write_csv
from sdar_tamp.plan_file import PlanFile


def _read(path: Path) -> tuple[list[str], list[list[str]]]:
    with path.open(encoding="utf-8", newline="") as stream:
        rows = list(csv.reader(stream))
    return rows[0], rows[1:]


@pytest.fixture(scope="module")
def table(plan: PlanFile, tmp_path_factory: pytest.TempPathFactory) -> tuple[list[str], list]:
    return _read(write_csv(plan, tmp_path_factory.mktemp("csv") / "plan.csv"))


def test_header_names_every_column(plan: PlanFile, table: tuple[list[str], list]) -> None:
    header, rows = table
    joints = [*plan.arms[0].joints, *plan.arms[1].joints]
    assert header == ["time", *joints, "left_gripper", "right_gripper", "left_held", "right_held"]
    assert header == csv_header(plan)
    assert all(len(r) == len(header) for r in rows)


def test_rows_at_50_hz_cover_the_plan(plan: PlanFile, table: tuple[list[str], list]) -> None:
    times = np.array([float(r[0]) for r in table[1]])
    assert times[0] == 0.0
    np.testing.assert_allclose(np.diff(times), 0.02, atol=1e-9)
    assert plan.duration <= times[-1] < plan.duration + 0.02


def test_positions_round_trip(plan: PlanFile, table: tuple[list[str], list]) -> None:
    times = np.array([float(r[0]) for r in table[1]])
    q = np.array([[float(x) for x in r[1:13]] for r in table[1]])
    expected = np.stack([np.interp(times, plan.t, plan.q[:, j]) for j in range(12)], axis=1)
    np.testing.assert_allclose(q, expected, rtol=0, atol=1e-12)  # linear between samples
    np.testing.assert_allclose(q[-1], plan.q[-1], atol=1e-12)  # the final configuration
    # re-interpolated at the plan's own times the table gives the plan back (up to the
    # linear interpolation error of 0.02 s rows: h^2 / 8 times the acceleration)
    back = np.stack([np.interp(plan.t, times, q[:, j]) for j in range(12)], axis=1)
    error = np.abs(back - plan.q).max()
    assert 0.0 < error < 0.02**2 / 8 * 5.0 * 2  # the plan's peak acceleration is < 5 rad/s^2


def test_gripper_columns_switch_at_the_events(
    plan: PlanFile, table: tuple[list[str], list]
) -> None:
    times = np.array([float(r[0]) for r in table[1]])
    closed = np.array([[int(r[13]), int(r[14])] for r in table[1]])
    held = [(r[15], r[16]) for r in table[1]]
    grasp, release_left, release_right = 0.8, plan.events[2].t, plan.events[3].t
    for k, t in enumerate(times):
        left = grasp <= t + 1e-12 and t < release_left - 1e-12
        right = grasp <= t + 1e-12 and t < release_right - 1e-12
        assert closed[k].tolist() == [int(left), int(right)], t
        assert held[k] == ("o1" if left else "", "o2" if right else ""), t
    assert closed[0].tolist() == [0, 0] and closed[-1].tolist() == [0, 0]


def test_other_rates_and_bad_rates(plan: PlanFile, tmp_path: Path) -> None:
    _, rows = _read(write_csv(plan, tmp_path / "10hz.csv", rate=10.0))
    assert len(rows) == int(np.ceil(plan.duration * 10 - 1e-9)) + 1
    for rate in (0.0, -5.0, float("nan"), float("inf")):
        with pytest.raises(ParameterError, match="rate must be"):
            write_csv(plan, tmp_path / "bad.csv", rate=rate)
    assert not (tmp_path / "bad.csv").exists()
