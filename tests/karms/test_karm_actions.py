"""Gripper actions of k arms into the plan file: several consecutive one-gripper ``pick`` (or
``place``) actions at one configuration, with no move between them, become one simultaneous
event (one instant, one dwell), as ``pick-both`` does for two arms."""

from __future__ import annotations

from typing import Any

import pytest
from karm_cells import SIZE, build, crossing, pick_place

from sdar_tamp.app.plan_export import ActionDecoder, timeline
from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.streams import parse_stream_file
from sdar_tamp.plan_building import GripperEvent
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.replay import validate_plan
from sdar_tamp.resources import domain_file
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import inverse
from solvers.solution import Action
from streams.grasps import sample_grasps


def _decoder() -> ActionDecoder:
    domain = parse_domain(domain_file("dual_arm_rearrangement").read_text(encoding="utf-8"))
    text = domain_file("dual_arm_rearrangement", "stream.pddl").read_text(encoding="utf-8")
    return ActionDecoder(domain, parse_stream_file(text, domain))


def _gripper_actions(name: str, moves: dict[str, tuple[str, Any, Any]], grasp: Any) -> list[Action]:
    """One ``pick`` or ``place`` per arm: ``(?a ?o ?p ?g ?q ?d)``, all at configuration d."""
    return [
        Action(name, (arm, m[0], f"p-{m[0]}", grasp, f"q-{arm}", "d")) for arm, m in moves.items()
    ]


def test_consecutive_picks_and_places_of_four_arms_are_simultaneous_events(
    cells: dict[int, Scene], instances: dict[int, Instance], plans: dict[int, PlanFile]
) -> None:
    scene, instance = cells[4], instances[4]
    moves = crossing(4)
    grasp = next(g for g in sample_grasps(SIZE, scene.grasp_limits) if g.tilt == 0.0)
    decoder = _decoder()
    picks = timeline(_gripper_actions("pick", moves, grasp), [], decoder)
    places = timeline(_gripper_actions("place", moves, grasp), [], decoder)
    assert [(e.arm, e.type, e.object) for e in picks] == [
        (arm, "grasp", m[0]) for arm, m in moves.items()
    ]
    assert all(isinstance(e, GripperEvent) for e in [*picks, *places])
    for e in picks:
        assert isinstance(e, GripperEvent)
        assert (e.T_tcp_object == inverse(grasp.T_object_tcp)).all()
    phases = pick_place(scene, moves)
    phases[2], phases[6] = picks, places  # the decoded events in place of the hand-made ones
    plan = build(scene, instance, phases)
    grasps = [e for e in plan.events if e.type == "grasp"]
    releases = [e for e in plan.events if e.type == "release"]
    assert len(grasps) == len(releases) == 4
    assert len({e.t for e in grasps}) == 1 and len({e.t for e in releases}) == 1
    # one dwell for the four grasps together: the same timeline as the hand-made plan's
    assert plan.duration == pytest.approx(plans[4].duration)
    report = validate_plan(instance, plan, scene)
    assert report.ok, report.violation
