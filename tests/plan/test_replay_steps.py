"""The replay stretch by stretch (:class:`sdar_tamp.replay_steps.StepValidator`): a valid plan
cut at its gripper events passes and meets the end rules; a plan on a changed world is
refused with the violation the whole replay finds."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_rules import Violation
from sdar_tamp.replay import validate_plan
from sdar_tamp.replay_steps import StepValidator
from sdar_tamp.resources import domain_file
from sdar_tamp.world.instance import Instance, Pose2D, load_instance
from sdar_tamp.world.scene import load_scene

SOLVED = Path(__file__).parent / "solved"


def _stretches(plan: PlanFile, cuts: int) -> Violation | None:
    """Check ``plan`` cut after its gripper events (every ``cuts``-th instant); the first
    violation, the end rules included."""
    path = domain_file("dual_arm_rearrangement", f"suites/paper/{plan.instance}.yaml")
    return _check(load_instance(path), plan, cuts)


def _check(instance: Instance, plan: PlanFile, cuts: int) -> Violation | None:
    checker = StepValidator(instance, load_scene(instance.scene_path()))
    instants = sorted({e.t for e in plan.events})[::cuts]
    start = 0
    for cut in [*instants, float(plan.t[-1])]:
        stop = int(np.searchsorted(plan.t, cut, side="right"))
        after = float(plan.t[start - 1]) if start else -1.0  # the last sample checked
        events = [e for e in plan.events if after < e.t <= cut]
        found = checker.check(plan.t[start:stop], plan.q[start:stop], events)
        if found is not None:
            return found
        start = stop
    return checker.finish()


@pytest.mark.parametrize("name", ["D5", "M2", "R5"])
@pytest.mark.parametrize("cuts", [1, 3])
def test_a_valid_plan_passes_stretch_by_stretch(name: str, cuts: int) -> None:
    plan = load_plan(SOLVED / f"{name}.plan.json")
    assert _stretches(plan, cuts) is None


def test_a_moved_object_is_refused_as_the_whole_replay_refuses_it() -> None:
    plan = load_plan(SOLVED / "M2.plan.json")
    instance = load_instance(domain_file("dual_arm_rearrangement", "suites/paper/M2.yaml"))
    first = plan.events[0].object
    objects = tuple(
        dataclasses.replace(o, start=Pose2D(o.start.x + 0.03, o.start.y, o.start.yaw))
        if o.name == first
        else o
        for o in instance.objects
    )
    moved = dataclasses.replace(instance, objects=objects)
    whole = validate_plan(moved, plan)
    assert whole.violation is not None
    found = _check(moved, plan, 1)
    assert found == whole.violation
