"""The repair's planning budget and its removed objects (``sdar_tamp.app.repair``; the repair
itself is tested through re-planning, ``test_replanning.py``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.app.config import PlannerConfig
from sdar_tamp.app.repair import repair_budget, without_gone
from sdar_tamp.app.replanning import replan
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_state import PlanState
from sdar_tamp.replay import validate_plan
from sdar_tamp.resources import domains_root
from sdar_tamp.world.instance import load_instance
from sdar_tamp.world.observed import parse_observed
from sdar_tamp.world.scene import load_scene

SOLVED = Path(__file__).parents[1] / "plan" / "solved"


@pytest.mark.parametrize(("limit", "budget"), [(60.0, 15.0), (30.0, 7.5), (8.0, 3.0), (2.0, 2.0)])
def test_the_repair_budget(limit: float, budget: float) -> None:
    """A quarter of the time limit, at least 3 s, never more than the limit."""
    assert repair_budget(limit) == pytest.approx(budget)


def test_a_removed_object_in_a_task_with_others_leaves_its_arm_moving_empty() -> None:
    """D5's second task carries o4 (left arm) and o1 (right arm) at once; o4 removed at 4.5 s
    (before its grasp at 5.711 s): the repair drops o4's grasp and release and keeps every
    motion (the left arm makes its trip with an empty gripper, no motion planned again),
    so the rest of the old plan is kept sample for sample and replays valid."""
    instance = load_instance(domains_root() / "dual_arm_rearrangement/suites/paper/D5.yaml")
    old = load_plan(SOLVED / "D5.plan.json")
    out = replan(instance, old, 4.5, parse_observed("removed: [o4]", "obs.yaml"),
                 config=PlannerConfig(max_time=60.0, seed=0), compare=False)  # fmt: skip
    assert out.status == "repaired" and out.changed and out.valid is True and out.plan is not None
    assert validate_plan(instance, out.plan, load_scene()).ok
    plan = out.plan
    assert not [e for e in plan.events if e.object == "o4"] and "o4" not in plan.final_poses
    kept = [(e.type, e.object) for e in old.events if e.object != "o4"]
    assert [(e.type, e.object) for e in plan.events] == kept
    shift = plan.duration - old.duration  # the hold at the cut, at most a few samples
    assert 0.0 <= shift < 0.1
    after = plan.t > out.resume
    assert np.allclose(plan.q[after], np.array([
        [np.interp(t - shift, old.t, old.q[:, j]) for j in range(old.q.shape[1])]
        for t in plan.t[after]
    ]), atol=1e-9)  # fmt: skip
    assert plan.metrics.actions == len(kept) // 2


def test_without_gone_keeps_tasks_of_gone_objects_only() -> None:
    """o2's task moves o2 alone: with o2 gone nothing is dropped (the repair replaces that
    task by a motion to the next one); with nothing gone the plan is the same object."""
    old = load_plan(SOLVED / "D5.plan.json")
    starts = {"o0": (0.0, 0.0, 0.0), "o1": (0.0, 0.0, 0.0), "o3": (0.0, 0.0, 0.0)}
    state = PlanState(8.4, old.q[0], {}, {**starts, "o4": (0.0, 0.0, 0.0)})
    assert without_gone(old, state) == (old, False)  # o2 gone, alone in its task
    everything = PlanState(0.0, old.q[0], {}, {n: (0.0, 0.0, 0.0) for n in
                                               ("o0", "o1", "o2", "o3", "o4")})  # fmt: skip
    assert without_gone(old, everything) == (old, False)
    dropped, changed = without_gone(old, PlanState(0.0, old.q[0], {}, {
        n: (0.0, 0.0, 0.0) for n in ("o1", "o2", "o3", "o4")}))  # fmt: skip
    assert changed and [e.object for e in dropped.events if e.t < 4.1] == ["o3", "o3"]
    assert all("o0" not in s.objects for s in dropped.steps if s.t_start < 4.08)
