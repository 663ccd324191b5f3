"""The retreat of arms that came down one after the other: the last one down goes up first.

``panda_place_both_retreat.json`` is a motion of the Panda cell (paper suite M1 generated in
``panda_facing``) from a two-arm placement, both arms at their objects, to the next picks:
the wrists of the two arms sit side by side above the table, so they cannot go up together,
nor the left arm first; the right arm first, then the left, is clear."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.world.cells import cell_path
from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.scene import load_scene
from streams.context import WorldContext
from streams.motion.exact_check import validate_trajectory
from streams.motion.ladder import _clear_phases
from streams.motion.planner import MotionPlanner
from streams.motion.records import MotionRequest
from streams.motion.waypoints import chain_arms

DATA = Path(__file__).resolve().parents[2] / "data" / "panda_place_both_retreat.json"


def test_chain_arms_moves_the_arms_in_the_order_given() -> None:
    a = np.array([[0.0], [1.0]])
    b = np.array([[10.0], [11.0], [12.0]])
    c = np.array([[20.0], [21.0]])
    layout = chain_arms([a, b, c])
    np.testing.assert_array_equal(layout[0], [[0, 10, 20], [1, 10, 20]])
    np.testing.assert_array_equal(layout[2], [[1, 12, 20], [1, 12, 21]])
    last_first = chain_arms([a, b, c], order=[2, 1, 0])
    np.testing.assert_array_equal(last_first[0], [[0, 10, 20], [0, 10, 21]])
    np.testing.assert_array_equal(last_first[1], [[0, 10, 21], [0, 11, 21], [0, 12, 21]])
    np.testing.assert_array_equal(last_first[2], [[0, 12, 21], [1, 12, 21]])


@pytest.fixture(scope="module")
def panda() -> MotionPlanner:
    return MotionPlanner(WorldContext.load(load_scene(cell_path("panda_facing"))))


def _request() -> MotionRequest:
    d = json.loads(DATA.read_text(encoding="utf-8"))
    objects = {k: ObjectBox(np.array(T), tuple(size)) for k, (T, size) in d["objects"].items()}
    return MotionRequest(
        np.array(d["q_start"]),
        np.array(d["q_goal"]),
        objects,
        retreat=tuple(d["retreat"]),
        approach=tuple(d["approach"]),
    )


def test_the_last_arm_down_retreats_first(panda: MotionPlanner) -> None:
    request = _request()
    panda.configure(request)

    def clear(**kw: bool) -> bool:
        phases = panda.phases(request, lift=panda.shape.default_lift, **kw)
        assert phases is not None
        path = np.concatenate(phases[0])
        return validate_trajectory(panda.ctx, panda.world, path, near=panda.near_world).ok

    assert not clear()  # together
    assert not clear(one_at_a_time=True)  # left, then right
    assert clear(one_at_a_time=True, last_first=True)  # right, then left
    found = _clear_phases(panda, request, one_at_a_time=False)
    assert not isinstance(found, str)
    first, second = found[0]
    left = panda.ctx.layout.slice("left")
    right = panda.ctx.layout.slice("right")
    assert np.ptp(first[:, left], axis=0).max() == 0.0 and np.ptp(first[:, right]) > 0.0
    assert np.ptp(second[:, right], axis=0).max() == 0.0 and np.ptp(second[:, left]) > 0.0
