"""Where a fresh continuation may start on a running plan (``sdar_tamp.app.replan_starts``):
D5's plan repaired for o4 nudged at 5.116 s (``conftest.py``). Its rest after the cut: the
arms go to o1 and o4 (5.73-6.99 s), carry them (7.49-9.15 s), then one arm goes to o2
(9.65-11.16 s) and carries it (11.66-13.18 s)."""

from __future__ import annotations

import numpy as np
import pytest

from sdar_tamp.app.cache import PlannerCache
from sdar_tamp.app.replan_starts import Start, at_grasps, next_start
from sdar_tamp.app.replanning import ReplanOutcome, fresh_continuation, replan
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_state import cut_point
from sdar_tamp.replay import validate_plan
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene, load_scene
from tests.app.conftest import CONFIG, O4_AT, o4_nudged

ABOVE = 0.05 + 0.015  # D5's objects are 5 cm tall


@pytest.fixture(scope="module")
def repaired(d5: tuple[Instance, PlanFile], cache: PlannerCache) -> ReplanOutcome:
    out = replan(*d5, O4_AT, o4_nudged(d5), config=CONFIG, cache=cache, compare=False)
    assert out.status == "repaired" and out.changed and out.plan is not None
    return out


@pytest.fixture(scope="module")
def scene() -> Scene:
    return load_scene()


def _start(
    d5: tuple[Instance, PlanFile], repaired: ReplanOutcome, scene: Scene, t: float,
    brakes: bool = True,
) -> Start | None:  # fmt: skip
    assert repaired.plan is not None
    starts = {o.name: o.start.as_tuple() for o in d5[0].objects}
    kins = {a: ArmKinematics.from_scene(scene, a) for a in scene.arm_names}
    return next_start(repaired.plan, t, starts, scene, kins, brakes=brakes, above=ABOVE)


def _tool_heights(scene: Scene, q: np.ndarray) -> list[float]:
    kins = {a: ArmKinematics.from_scene(scene, a) for a in scene.arm_names}
    return [float(kins[a].fk_tcp(scene.layout.part(q, a))[2, 3]) for a in scene.arm_names]


def test_at_rest_the_start_is_the_clear_cut_there(
    d5: tuple[Instance, PlanFile], repaired: ReplanOutcome, scene: Scene
) -> None:
    start = _start(d5, repaired, scene, repaired.resume)
    assert start is not None and not start.braked and not start.free
    assert start.t == pytest.approx(repaired.resume)
    assert set(start.resting) == {"o0", "o1", "o2", "o3", "o4"}


def test_on_the_way_to_grasps_the_arms_brake_high_enough(
    d5: tuple[Instance, PlanFile], repaired: ReplanOutcome, scene: Scene
) -> None:
    """At 6.2 s the arms fly to o1 and o4 with empty grippers: a braked stop from the sample
    there, on the plan's path, at rest, the tools over the objects, both arms free; at
    5.8 s they still rise from where they stood (tools low): the stop is the first one
    high enough, later in that motion."""
    plan = repaired.plan
    assert plan is not None
    start = _start(d5, repaired, scene, 6.2)
    assert start is not None and start.braked and start.free == {"left", "right"}
    assert 6.2 <= start.t < 6.25
    prefix = start.prefix
    before = prefix.t <= start.t
    assert np.array_equal(prefix.q[before], plan.q[plan.t <= start.t])  # the plan up to it
    assert np.abs(prefix.q[-1] - prefix.q[-2]).max() == 0.0  # ends at rest
    assert min(_tool_heights(scene, prefix.q[-1])) >= ABOVE
    assert prefix.events == tuple(e for e in plan.events if e.t < start.t)
    rising = _start(d5, repaired, scene, 5.8)
    assert rising is not None and rising.braked and 5.8 < rising.t < 6.2
    assert rising.prefix is not None and min(_tool_heights(scene, rising.prefix.q[-1])) >= ABOVE


def test_while_an_arm_holds_an_object_the_start_is_the_next_clear_cut(
    d5: tuple[Instance, PlanFile], repaired: ReplanOutcome, scene: Scene
) -> None:
    """Carrying (8.0 s), or coming down to the grasps (6.95 s, the tools low): no braked
    stop; the next clear cut after the releases at 9.15 s, not the grasps' cut."""
    plan = repaired.plan
    assert plan is not None
    for t in (8.0, 6.95):
        start = _start(d5, repaired, scene, t)
        assert start is not None and not start.braked and 9.15 < start.t < 9.2
        assert not at_grasps(plan, cut_point(plan, start.t))


def test_without_brakes_only_clear_cuts_and_none_past_the_end(
    d5: tuple[Instance, PlanFile], repaired: ReplanOutcome, scene: Scene
) -> None:
    plan = repaired.plan
    assert plan is not None
    start = _start(d5, repaired, scene, 6.2, brakes=False)
    assert start is not None and not start.braked and 9.15 < start.t < 9.2
    assert _start(d5, repaired, scene, plan.duration) is None


def test_a_continuation_from_a_braked_stop_replays_valid(
    d5: tuple[Instance, PlanFile], repaired: ReplanOutcome, scene: Scene,
    cache: PlannerCache,
) -> None:  # fmt: skip
    """A fresh SDAR continuation from the braked stop at 6.2 s (the arms leave directly from
    where they stopped), spliced after it: the independent replay accepts the whole plan."""
    start = _start(d5, repaired, scene, 6.2)
    assert start is not None and start.braked
    world = cache.world(d5[0].scene_path(), CONFIG.trajopt)
    sizes = {o.name: o.size for o in d5[0].objects}
    fresh = fresh_continuation(world, CONFIG, d5[0], start.prefix, dict(start.resting), sizes,
                               start.free, prove=False)  # fmt: skip
    assert fresh.plan is not None
    report = validate_plan(d5[0], fresh.plan, scene)
    assert report.ok, report.violation
    assert fresh.plan.observations == start.prefix.observations
    placed = {e.object for e in fresh.plan.events if e.type == "release" and e.t > start.t}
    assert placed >= {"o1", "o2", "o4"}  # the objects the repair had still to move
