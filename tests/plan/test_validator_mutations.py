"""Mutation test of the independent validator.

A valid dual-arm plan is made once with the planning streams (both arms pick at once, carry
at once and place at once; o3 never moves). Several hundred mutants of it, each breaking one
rule (limits by a few percent, dwells, event times, jumps, time stamps, non-finite values,
joint names, swapped arms, collisions, misplaced objects, drops in mid-air ...), must all be
rejected with a violation of a relevant kind; plans changed in ways that keep them valid
(slower, longer pauses, exact limits) must be accepted.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from sdar_tamp.cli import main
from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import GRIPPER_DWELL, PlanFile, PlanFileError
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_writing import plan_to_dict, save_plan
from sdar_tamp.replay import PlanValidator, ReplayReport, validate_plan
from sdar_tamp.world.scene import Scene
from streams.context import WorldContext
from streams.motion.optimiser_cache import OptimiserCache
from streams.motion.planner import MotionPlanner
from tests.plan.mutant_base import (
    HOME_PAUSE,
    INSTANCE,
    JOINTS,
    Base,
    Mutant,
    acceleration,
    index,
    insert_still,
    instants,
    make_base,
    rebuild,
    remove,
    rest_junctions,
    scene_arms,
    velocity,
    with_events,
    with_q,
)
from tests.plan.mutant_timing import TIMING_FAMILIES
from tests.plan.mutant_world import WORLD_FAMILIES, arm_offsets

FAMILIES = TIMING_FAMILIES + WORLD_FAMILIES


@pytest.fixture(scope="module")
def base(ctx: WorldContext, planner: MotionPlanner, optimisers: OptimiserCache) -> Base:
    return make_base(ctx, planner, optimisers)


def _validate(b: Base, m: Mutant) -> ReplayReport:
    instance = m.instance or b.instance
    if m.scene is not None:
        return PlanValidator(m.scene, max_tcp_step=0.05).validate(instance, m.plan)
    return (b.fine if m.fine else b.coarse).validate(instance, m.plan)


# -- tests -------------------------------------------------------------------------------------
def test_the_base_plan_is_valid(base: Base) -> None:
    report = base.fine.validate(base.instance, base.plan)
    assert report.ok, report.violation
    assert [(e.arm, e.type) for e in base.plan.events] == [
        ("left", "grasp"),
        ("right", "grasp"),
        ("left", "release"),
        ("right", "release"),
    ]
    assert base.plan.metrics.dual_arm_steps == 3
    assert len(rest_junctions(base.plan)) >= 1


def test_every_invalid_mutant_is_rejected_with_a_relevant_violation(base: Base) -> None:
    mutants = [m for family in FAMILIES for m in family(base)]
    wrong: list[str] = []
    kinds: Counter[str] = Counter()
    for m in mutants:
        v = _validate(base, m).violation
        if v is None:
            wrong.append(f"{m.family} / {m.name}: accepted")
        elif v.kind not in m.expect or m.mention not in v.message:
            wrong.append(f"{m.family} / {m.name}: {v.kind}: {v.message}")
        else:
            kinds[v.kind] += 1
    assert wrong == [], f"{len(wrong)} of {len(mutants)} mutants:\n" + "\n".join(wrong)
    assert len(mutants) >= 400
    families = Counter(m.family for m in mutants)
    assert min(families.values()) >= 4, families
    every_kind = {
        "format",
        "scene",
        "instance",
        "joint limit",
        "velocity",
        "acceleration",
        "dwell",
        "collision",
        "grasp",
        "release",
        "held",
        "goal",
        "final poses",
    }
    assert every_kind <= set(kinds), every_kind - set(kinds)


def test_some_arm_offsets_make_the_arms_collide(base: Base) -> None:
    """Arm against arm (not a gripper against the table or an object)."""
    between: list[str] = []
    for m in arm_offsets(base):
        v = _validate(base, m).violation
        assert v is not None
        text = v.message
        if text.startswith("arms "):  # the arms in contact, then the shapes
            assert text.startswith("arms left and right in contact: "), text
            text = text.split(": ", 1)[1]
        pairs = [p.split(" with ") for p in text.split(", ") if " with " in p]
        sides = [{a.split("_")[0], c.split("_")[0]} for a, c in pairs]
        if v.kind == "collision" and {"left", "right"} in sides:
            between.append(m.name)
    assert len(between) >= 1


def _slower(plan: PlanFile, k: int) -> PlanFile:
    """Everything ``k`` times slower, every interval cut into ``k`` equal ones."""
    t, q = plan.t, plan.q
    frac = np.arange(k) / k
    t_new = np.append((t[:-1, None] + frac * np.diff(t)[:, None]).ravel(), t[-1]) * k
    q_new = np.concatenate(
        [(q[:-1, None] + frac[:, None] * np.diff(q, axis=0)[:, None]).reshape(-1, 12), q[-1:]]
    )
    return rebuild(plan, np.arange(len(t)) * k, t_new, q_new)


def _valid_variants(b: Base) -> Iterator[tuple[str, PlanFile, Scene | None]]:
    plan, scene = b.plan, b.ctx.scene
    yield "slower x2", _slower(plan, 2), None
    yield "slower x3", _slower(plan, 3), None
    for t_e in instants(plan):
        yield f"longer dwell at {t_e:.2f}", insert_still(plan, index(plan, t_e), 10), None
    yield "still at the start", insert_still(plan, 0, HOME_PAUSE), None
    yield "still at the end", insert_still(plan, len(plan.t) - 1, HOME_PAUSE), None
    for k in rest_junctions(plan)[:3]:
        yield f"pause at rest {k}", insert_still(plan, k, HOME_PAUSE), None
    final = dict(plan.final_poses)
    x, y, yaw = final["o1"]
    final["o1"] = (x, y, yaw - math.pi)
    yield "final yaw - pi", dataclasses.replace(plan, final_poses=final), None
    # limits exactly at what the plan uses
    v, a = np.abs(velocity(plan)), np.abs(acceleration(plan))
    for j in range(12):
        at = scene_arms(scene, j, "velocity_limit", float(v[:, j].max()) or 1.0)
        at = scene_arms(at, j, "acceleration_limit", float(a[:, j].max()) or 1.0)
        at = scene_arms(at, j, "upper", float(plan.q[:, j].max()))
        at = scene_arms(at, j, "lower", float(plan.q[:, j].min()))
        yield f"limits at the plan's extremes, {JOINTS[j]}", plan, at


def test_valid_preserving_mutants_are_accepted(base: Base) -> None:
    names = []
    for name, plan, scene in _valid_variants(base):
        if scene is None:
            report = base.coarse.validate(base.instance, plan)
        else:
            report = PlanValidator(scene, max_tcp_step=0.05).validate(base.instance, plan)
        assert report.ok, f"{name}: {report.violation}"
        names.append(name)
    assert len(names) >= 20
    slower = _slower(base.plan, 2)
    assert slower.duration == pytest.approx(2 * base.plan.duration)
    assert base.fine.validate(base.instance, slower).ok


def test_a_plan_file_round_trip_stays_valid(base: Base, tmp_path: Path) -> None:
    plan = load_plan(save_plan(base.plan, tmp_path / "plan.json"))
    assert base.fine.validate(base.instance, plan).ok


def test_mutant_files_are_refused_by_the_loader_and_the_command_line(
    base: Base, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Non-finite numbers and times out of order cannot even be loaded (exit status 2);
    wrong joint names load and are invalid (exit status 1)."""
    instance = tmp_path / "d3.yaml"
    instance.write_text(INSTANCE)
    data = plan_to_dict(base.plan)

    def nan(d: dict[str, Any]) -> None:
        d["trajectory"]["q"][3][2] = math.nan

    def repeated_time(d: dict[str, Any]) -> None:
        d["trajectory"]["t"][5] = d["trajectory"]["t"][4]

    edits = {"nan": nan, "repeated time": repeated_time}
    for name, edit in edits.items():
        bad = json.loads(json.dumps(data))
        edit(bad)
        path = tmp_path / f"{name}.json"
        path.write_text(json.dumps(bad))  # NaN written as the (non-JSON) token NaN
        with pytest.raises(PlanFileError, match=r"trajectory\.(q\[3\]\[2\]|t\[5\])"):
            load_plan(path)
        assert main(["validate", str(instance), str(path)]) == 2
    joints = list(data["arms"][1]["joints"])
    joints[2], joints[3] = joints[3], joints[2]
    data["arms"][1]["joints"] = joints
    path = tmp_path / "joints.json"
    path.write_text(json.dumps(data))
    capsys.readouterr()
    assert main(["validate", str(instance), str(path)]) == 1
    out = capsys.readouterr().out
    assert "scene: arms[1].joints[2]: expected 'right_elbow_joint'" in out


def test_validator_parameters_are_checked(base: Base) -> None:
    for kwargs in (
        {"max_tcp_step": 0.0},
        {"dwell": -0.1},
        {"velocity_tolerance": -1e-6},
        {"acceleration_tolerance": math.nan},
    ):
        with pytest.raises(ParameterError, match=next(iter(kwargs))):
            PlanValidator(base.ctx.scene, **kwargs)  # type: ignore[arg-type]


def test_the_dwell_is_the_format_s_and_a_shorter_one_can_be_asked(base: Base) -> None:
    plan = remove(base.plan, index(base.plan, instants(base.plan)[0]) + 1, 10)  # 0.3 s left
    report = base.coarse.validate(base.instance, plan)
    assert report.violation is not None and report.violation.kind == "dwell"
    assert report.violation.t == pytest.approx(instants(base.plan)[0])
    assert f"still for {GRIPPER_DWELL} s" in report.violation.message
    assert validate_plan(base.instance, plan, base.ctx.scene, 0.05, dwell=0.3).ok


def test_format_rules_for_plans_built_in_memory(base: Base) -> None:
    plan = base.plan
    left, right = plan.arms
    e = plan.events[0]
    cases: dict[str, tuple[PlanFile, str]] = {
        "no samples": (
            dataclasses.replace(plan, t=np.zeros(0), q=np.zeros((0, 12)), events=()),
            "trajectory.t: expected a non-empty list",
        ),
        "q rows": (with_q(plan, plan.q[:-1]), "trajectory.q: expected shape"),
        "q columns": (with_q(plan, plan.q[:, :11]), "trajectory.q: expected shape"),
        "event arm": (
            with_events(plan, [dataclasses.replace(e, arm="middle"), *plan.events[1:]]),
            "events[0]: expected an arm of ['left', 'right']",
        ),
        "event type": (
            with_events(plan, [dataclasses.replace(e, type="squeeze"), *plan.events[1:]]),
            "and a type of ['grasp', 'release'], got 'left', 'squeeze'",
        ),
        "event transform": (
            with_events(plan, [dataclasses.replace(e, T_tcp_object=2.0 * np.eye(4))]),
            "events[0].T_tcp_object: expected a finite rigid transform",
        ),
        "five joints": (
            dataclasses.replace(
                plan, arms=(left, dataclasses.replace(right, joints=right.joints[:5]))
            ),
            "arms[1].joints: the scene's arm 'right' has 6 joints",
        ),
        "seven joints": (
            dataclasses.replace(
                plan, arms=(dataclasses.replace(left, joints=(*left.joints, "x")), right)
            ),
            "arms[0].joints: the scene's arm 'left' has 6 joints",
        ),
    }
    for name, (mutant, text) in cases.items():
        report = base.coarse.validate(base.instance, mutant)
        assert report.violation is not None, name
        assert report.violation.kind in ("format", "scene") and text in report.violation.message, (
            name,
            report.violation,
        )
        assert report.checks == 0


def test_without_a_dwell_only_the_events_matter(base: Base) -> None:
    """``dwell=0``: an event may come right before the robot moves on."""
    plan = remove(base.plan, index(base.plan, instants(base.plan)[0]) + 1, 25)
    assert base.coarse.validate(base.instance, plan).violation.kind == "dwell"  # type: ignore[union-attr]
    assert validate_plan(base.instance, plan, base.ctx.scene, 0.05, dwell=0.0).ok
