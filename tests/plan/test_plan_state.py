"""The state at a time of a plan, its cut points and prefixes, and plan files that record an
observation: read, written, and replayed by the validator (the observed arrangement replaces
the planned one at its time)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import GRIPPER_DWELL, MAX_DT, PlanFile, PlanFileError, PlanObservation
from sdar_tamp.plan_reading import load_plan, plan_from_dict
from sdar_tamp.plan_rules import check_timeline
from sdar_tamp.plan_state import cut_point, prefix_plan, state_at
from sdar_tamp.plan_writing import plan_to_dict, save_plan
from sdar_tamp.replay import validate_plan
from sdar_tamp.resources import domains_root
from sdar_tamp.world.instance import Instance, load_instance
from sdar_tamp.world.scene import Scene, load_scene

SOLVED = Path(__file__).parent / "solved"


@pytest.fixture(scope="module")
def d5() -> tuple[Instance, PlanFile, Scene]:
    instance = load_instance(domains_root() / "dual_arm_rearrangement/suites/paper/D5.yaml")
    return instance, load_plan(SOLVED / "D5.plan.json"), load_scene()


def _starts(instance: Instance) -> dict[str, tuple[float, float, float]]:
    return {o.name: o.start.as_tuple() for o in instance.objects}


def test_the_state_follows_the_events(d5: tuple[Instance, PlanFile, Scene]) -> None:
    instance, plan, scene = d5
    first = plan.events[0]  # two grasps at one instant: o3 by left, o0 by right
    at_start = state_at(plan, _starts(instance), scene, 0.0)
    assert at_start.held == {} and at_start.resting == _starts(instance)
    carrying = state_at(plan, _starts(instance), scene, first.t + 1.0)
    assert carrying.held == {"left": "o3", "right": "o0"}
    assert set(carrying.resting) == {"o1", "o2", "o4"} and carrying.holder["o3"] == "left"
    assert np.allclose(carrying.q, [np.interp(first.t + 1.0, plan.t, plan.q[:, j])
                                    for j in range(plan.q.shape[1])])  # fmt: skip
    at_grasp = state_at(plan, _starts(instance), scene, first.t)  # events strictly before t
    assert at_grasp.held == {}
    end = state_at(plan, _starts(instance), scene, plan.duration)
    assert end.held == {}
    for name, pose in plan.final_poses.items():
        assert np.allclose(end.resting[name], pose, atol=1e-6)


def test_a_time_outside_the_plan_is_refused(d5: tuple[Instance, PlanFile, Scene]) -> None:
    instance, plan, scene = d5
    for t in (-0.1, plan.duration + 1.0, float("nan")):
        with pytest.raises(ParameterError, match=r"at: expected a time within the plan"):
            state_at(plan, _starts(instance), scene, t)


def test_cut_points_are_at_rest_with_empty_grippers(d5: tuple[Instance, PlanFile, Scene]) -> None:
    _, plan, _ = d5
    grasp, release = plan.events[0].t, plan.events[2].t
    cut = cut_point(plan, 0.5)  # moving to the first grasps: cut before they happen
    assert cut.t == pytest.approx(grasp) and cut.events == 0
    cut = cut_point(plan, grasp + 0.1)  # carrying: after the releases
    assert cut.events == 4 and release < cut.t <= release + GRIPPER_DWELL + 1e-9
    assert cut_point(plan, plan.duration).index == len(plan.t) - 1
    for t in np.linspace(0.0, plan.duration, 23):
        cut = cut_point(plan, float(t))
        assert cut.t >= t - 1e-9
        i = cut.index
        still = [np.abs(plan.q[j + 1] - plan.q[j]).max() <= 1e-9 for j in (i - 1, i)
                 if 0 <= j < len(plan.t) - 1]  # fmt: skip
        assert any(still) or i == len(plan.t) - 1


def test_a_prefix_holds_still_and_any_plan_from_rest_may_follow(
    d5: tuple[Instance, PlanFile, Scene],
) -> None:
    _, plan, scene = d5
    cut = cut_point(plan, 0.5)
    prefix = prefix_plan(plan, cut)
    assert prefix.events == () and prefix.t[-1] == pytest.approx(cut.t + MAX_DT)
    assert np.array_equal(prefix.q[-1], plan.q[cut.index])
    assert check_timeline(prefix, scene) is None
    after = prefix_plan(plan, cut_point(plan, plan.events[0].t + 0.1))
    assert len(after.events) == 4 and after.t[-1] >= after.events[-1].t + GRIPPER_DWELL - 1e-9
    assert check_timeline(after, scene) is None
    holding = dataclasses.replace(cut, index=int(np.searchsorted(plan.t, plan.events[0].t + 1.0)),
                                  t=plan.events[0].t + 1.0, events=2)  # fmt: skip
    with pytest.raises(ParameterError, match="an arm holds an object there"):
        prefix_plan(plan, holding)


def _observed(plan: PlanFile, t: float, resting: dict[str, tuple[float, float, float]],
              added: dict[str, tuple[float, float, float]] | None = None) -> PlanFile:  # fmt: skip
    return dataclasses.replace(plan, observations=(PlanObservation(t, resting, added or {}),))


def test_observations_are_written_and_read(d5: tuple[Instance, PlanFile, Scene],
                                           tmp_path: Path) -> None:  # fmt: skip
    instance, plan, _ = d5
    assert "observations" not in plan_to_dict(plan)  # plans without any: as before
    seen = _observed(plan, 0.5, _starts(instance), {"b1": (0.05, 0.05, 0.05)})
    back = load_plan(save_plan(seen, tmp_path / "p.json"))
    assert back.observations == seen.observations


@pytest.mark.parametrize(
    ("edit", "key", "message"),
    [
        ({"t": -1.0}, "observations[0].t", "expected a time within the trajectory"),
        ({"added": {"b1": [0.1, 0.0, 0.1]}}, "observations[0].added.b1", "side lengths > 0"),
        ({"resting": {"o1": [0.0, 0.0]}}, "observations[0].resting.o1", "expected 3 numbers"),
        ({"extra": 1}, "observations[0].extra", "unexpected key"),
    ],
)
def test_bad_observations_are_refused_at_their_key(
    d5: tuple[Instance, PlanFile, Scene], edit: dict[str, object], key: str, message: str,
    tmp_path: Path,
) -> None:  # fmt: skip
    instance, plan, _ = d5
    data = plan_to_dict(_observed(plan, 0.5, _starts(instance)))
    data["observations"][0].update(edit)
    with pytest.raises(PlanFileError) as err:
        plan_from_dict(data, "p.json")
    assert err.value.key == key and message in err.value.detail
    path = tmp_path / "p.json"
    path.write_text(json.dumps(data, indent=1), encoding="utf-8")
    with pytest.raises(PlanFileError, match=r"p\.json:\d+:\d+: " + key.replace("[", r"\[")
                       .replace("]", r"\]")):  # fmt: skip
        load_plan(path)


def test_the_validator_replays_an_observation(d5: tuple[Instance, PlanFile, Scene]) -> None:
    instance, plan, scene = d5
    starts = _starts(instance)
    same = _observed(plan, 0.5, starts)  # what the plan assumed: still valid
    assert validate_plan(instance, same, scene).ok
    x, y, yaw = starts["o3"]
    nudged = _observed(plan, 0.5, {**starts, "o3": (x + 0.02, y, yaw + 0.2)})
    report = validate_plan(instance, nudged, scene)
    assert report.violation is not None and report.violation.kind in ("grasp", "collision")
    assert report.violation.t > 0.5
    overlapping = _observed(plan, 0.5, {**starts, "o3": starts["o1"]})
    report = validate_plan(instance, overlapping, scene)
    assert report.violation is not None and report.violation.kind == "observation"
    assert "overlapping" in report.violation.message and report.violation.t == 0.5
    outside = _observed(plan, 0.5, {**starts, "o3": (5.0, 0.0, 0.0)})
    report = validate_plan(instance, outside, scene)
    assert report.violation is not None and "outside the workspace" in report.violation.message
    held = _observed(plan, plan.events[0].t + 1.0, starts)  # o3 and o0 are held then
    report = validate_plan(instance, held, scene)
    assert report.violation is not None and report.violation.kind == "observation"
    assert "is seen resting but" in report.violation.message
    unknown = _observed(plan, 0.5, {**starts, "zz": (0.0, 0.25, 0.0)})
    report = validate_plan(instance, unknown, scene)
    assert report.violation is not None and report.violation.kind == "observation"
    assert "zz is neither the instance's nor added" in report.violation.message


def test_an_object_gone_at_the_end_needs_no_goal(d5: tuple[Instance, PlanFile, Scene]) -> None:
    instance, plan, scene = d5
    end = state_at(plan, _starts(instance), scene, plan.duration)
    final = dict(plan.final_poses)
    resting = dict(end.resting)
    del resting["o2"], final["o2"]
    t = plan.duration - 1e-3
    gone = dataclasses.replace(_observed(plan, t, resting), final_poses=final)
    assert validate_plan(instance, gone, scene).ok
    stale = _observed(plan, t, resting)  # final_poses still names o2
    report = validate_plan(instance, stale, scene)
    assert report.violation is not None and report.violation.kind == "final poses"
    assert "['o2']" in report.violation.message


def test_the_instance_rule_with_observations(d5: tuple[Instance, PlanFile, Scene]) -> None:
    instance, plan, scene = d5
    starts = _starts(instance)
    first = PlanObservation(1.0, starts, {})
    unsorted = dataclasses.replace(plan, observations=(first, dataclasses.replace(first, t=0.5)))
    report = validate_plan(instance, unsorted, scene)
    assert report.violation is not None and report.violation.kind == "format"
    assert "observations[1].t: expected sorted times" in report.violation.message
    stranger = dataclasses.replace(
        plan, observations=(first,),
        events=(dataclasses.replace(plan.events[0], object="zz"), *plan.events[1:]),
    )  # fmt: skip
    report = validate_plan(instance, stranger, scene)
    assert report.violation is not None and report.violation.kind == "instance"
    assert "['zz'] are neither the instance's nor added once" in report.violation.message
    clash = dataclasses.replace(
        plan, observations=(PlanObservation(1.0, starts, {"o1": (0.1,) * 3}),)
    )
    report = validate_plan(instance, clash, scene)
    assert report.violation is not None and report.violation.kind == "instance"
    assert "['o1']" in report.violation.message


def test_the_plan_schema_takes_observations(d5: tuple[Instance, PlanFile, Scene]) -> None:
    jsonschema = pytest.importorskip("jsonschema")
    from sdar_tamp.schemas import schema

    instance, plan, _ = d5
    seen = _observed(plan, 0.5, _starts(instance), {"b1": (0.05, 0.05, 0.05)})
    document = json.loads(json.dumps(plan_to_dict(seen)))
    validator = jsonschema.Draft202012Validator(schema("plan"))
    assert not list(validator.iter_errors(document))
    document["observations"][0]["added"]["b1"] = [0.05, -1.0, 0.05]
    assert list(validator.iter_errors(document))
    observed = jsonschema.Draft202012Validator(schema("observed"))
    good = {"poses": [{"name": "o1", "pose": [0, 0, 0.1]}], "removed": ["o2", 7],
            "added": [{"name": "b1", "size": [0.05, 0.05, 0.05], "pose": [0, 0.1, 0]}]}  # fmt: skip
    assert not list(observed.iter_errors(good)) and not list(observed.iter_errors(None))
    for bad in ({"removed": [True]}, {"moved": []}, {"added": [{"name": "b1", "pose": [0, 0, 0]}]}):
        assert list(observed.iter_errors(bad)), bad
