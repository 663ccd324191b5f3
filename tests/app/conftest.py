"""Shared cases of the re-planning tests: D5 of the paper suite with its stored plan, one
planner cache per module, and helpers that re-plan it from an observation written as YAML
(``test_replanning.py``, ``test_replanning_braking.py``, ``test_replan_moving.py``,
``test_replan_starts.py``)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.app.cache import PlannerCache
from sdar_tamp.app.config import PlannerConfig
from sdar_tamp.app.replanning import ReplanOutcome, replan
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_state import state_at
from sdar_tamp.replay import validate_plan
from sdar_tamp.resources import domains_root
from sdar_tamp.world.instance import Instance, ObjectSpec, load_instance
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.observed import ObservedState, parse_observed
from sdar_tamp.world.scene import load_scene

SOLVED = Path(__file__).parents[1] / "plan" / "solved"
AT = 4.5  # D5's plan: o3/o0 swapped, o4/o1 on their way; o2 rests until the last task
O4_AT = 5.116  # D5's plan: o4 resting, its task still to come
CONFIG = PlannerConfig(max_time=60.0, seed=0)


@pytest.fixture(scope="module")
def cache() -> PlannerCache:
    return PlannerCache()


@pytest.fixture(scope="module")
def d5() -> tuple[Instance, PlanFile]:
    instance = load_instance(domains_root() / "dual_arm_rearrangement/suites/paper/D5.yaml")
    return instance, load_plan(SOLVED / "D5.plan.json")


def o4_nudged(d5: tuple[Instance, PlanFile]) -> ObservedState:
    """o4 nudged at :data:`O4_AT`: the repair plans its task again (13.70 s in all), a fresh
    continuation from the same cut ends 0.5 s earlier (``test_replanning.py``)."""
    instance, plan = d5
    starts = {o.name: o.start.as_tuple() for o in instance.objects}
    x, y, yaw = state_at(plan, starts, load_scene(), O4_AT).resting["o4"]
    text = f"poses: [{{name: o4, pose: [{x + 0.0052}, {y + 0.0173}, {yaw - 0.1559}]}}]"
    return parse_observed(text, "obs.yaml")


def obj(instance: Instance, name: str) -> ObjectSpec:
    return next(o for o in instance.objects if o.name == name)


def replan_d5(d5: tuple[Instance, PlanFile], cache: PlannerCache, text: str, at: float = AT,
              **kw: object) -> ReplanOutcome:  # fmt: skip
    """D5's plan re-planned at ``at`` [s] from the observation ``text`` (``obs.yaml``)."""
    instance, plan = d5
    return replan(instance, plan, at, parse_observed(text, "obs.yaml"), config=CONFIG,
                  cache=cache, **kw)  # type: ignore[arg-type]  # fmt: skip


def grasp_poses(plan: PlanFile, name: str, after: float) -> list[tuple[float, float, float]]:
    """Where ``plan``'s grasps of ``name`` after ``after`` [s] take the object from."""
    scene = load_scene()
    out = []
    for e in plan.events:
        if e.object == name and e.type == "grasp" and e.t > after:
            q = np.array([np.interp(e.t, plan.t, plan.q[:, j]) for j in range(plan.q.shape[1])])
            T = ArmKinematics.from_scene(scene, e.arm).fk_tcp(scene.layout.part(q, e.arm))
            T = T @ e.T_tcp_object
            out.append((float(T[0, 3]), float(T[1, 3]), math.atan2(T[1, 0], T[0, 0])))
    return out


def assert_valid_whole(d5: tuple[Instance, PlanFile], out: ReplanOutcome) -> PlanFile:
    """``out``'s plan: valid by the independent replay, the old plan up to the cut, the
    observation at :data:`AT` recorded."""
    instance, old = d5
    assert out.plan is not None and out.valid is True, out
    report = validate_plan(instance, out.plan, load_scene())  # the independent replay again
    assert report.ok, report.violation
    prefix = out.plan.t <= out.cut
    assert np.array_equal(out.plan.q[prefix], old.q[old.t <= out.cut])  # the executed prefix
    assert [o.t for o in out.plan.observations] == [AT]
    return out.plan
