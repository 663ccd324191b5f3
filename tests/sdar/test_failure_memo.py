"""Grounding failures remembered across assignments and decisions (solvers/sdar/failure_memo.py)
and the pairwise checks of arms that feed them (solvers/sdar/arm_pairs.py)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import pytest

from sdar_tamp.app.problem import rearrangement_problem, table_plane
from sdar_tamp.world.instance import load_instance
from solvers.sdar.arm_pairs import AT_PICK, AT_PLACE, ArmPairs, PairTable, grippers_can_clear
from solvers.sdar.attempts import MotionMode
from solvers.sdar.failure_memo import FailureMemo, neighbourhood
from solvers.sdar.grounding import Grounding, Option
from solvers.sdar.options import SdarOptions
from solvers.sdar.sdar_t import SdarTaskPlanner
from solvers.sdar.solver import SdarSolver
from solvers.sdar.tasks import Move, Step
from streams.context import WorldContext

DATA = Path(__file__).parent / "data"


def test_a_failure_is_recalled_while_its_world_holds_and_forgotten_when_an_object_moves() -> None:
    memo = FailureMemo()
    memo.remember(("k",), "they meet", {"a": "p1", "b": "p2"})
    assert memo.recall(("k",), {"a": "p1", "b": "p2", "c": "p9"}) == "they meet"
    assert memo.recall(("k",), {"a": "p1", "b": "p2", "c": "p8"}) == "they meet"  # c: not its
    assert memo.hits == 2 and memo.forgotten == 0
    assert memo.recall(("k",), {"a": "p1", "b": "p3"}) is None  # b moved
    assert memo.forgotten == 1 and len(memo) == 0
    assert memo.recall(("k",), {"a": "p1", "b": "p2"}) is None  # forgotten for good
    memo.remember(("k",), "they meet", {"a": "p1"})
    assert memo.recall(("k",), {"b": "p2"}) is None  # a lifted
    assert memo.recall(("other",), {"a": "p1"}) is None


class _Cell:
    """A combine stream of four arms at home ``h``: ``north`` at ``x`` meets ``south`` at ``y``
    (and at ``y2``), ``west`` at ``bad`` meets an arm at home; counts the checks."""

    def __init__(self) -> None:
        self.calls = 0

    def __call__(self, confs: Mapping[str, str]) -> str | None:
        self.calls += 1
        if confs.get("north") == "x" and confs.get("south") in ("y", "y2"):
            return None
        if "bad" in confs.values():
            return None
        return "d"


def _option(pick: str, place: str) -> Option:
    return Option("g", pick, "t", place)


STEP = Step((Move("o1"), Move("o2"), Move("o3")), "rotate", 1)
POSES = {"o1": "p1", "o2": "p2", "o3": "p3"}


def test_two_arms_that_meet_whatever_their_options_fail_the_step_and_are_remembered() -> None:
    cell, memo = _Cell(), FailureMemo()
    pairs = ArmPairs(cell, memo)
    arms = ("north", "south", "east")
    per_move = [[_option("x", "x")], [_option("y", "q"), _option("y2", "q")], [_option("z", "z")]]
    assert pairs.table(STEP, arms, per_move, POSES, stage=(2, 6)) == AT_PICK
    checks = cell.calls
    # another assignment with the same two arms on the same two moves: recalled, no check
    assert pairs.meets(STEP, ("north", "south", "west"), (2, 6), POSES) == AT_PICK
    assert cell.calls == checks and memo.hits == 1
    # not for other arms, nor another stage (more options may clear them)
    assert pairs.meets(STEP, ("south", "north", "east"), (2, 6), POSES) is None
    assert pairs.meets(STEP, arms, (3, 6), POSES) is None
    # an object that moves takes the failure with it; one that is not its object does not
    assert pairs.meets(STEP, arms, (2, 6), {**POSES, "o3": "elsewhere"}) == AT_PICK
    assert pairs.meets(STEP, arms, (2, 6), {**POSES, "o2": "elsewhere"}) is None
    assert pairs.meets(STEP, arms, (2, 6), POSES) is None


def test_clear_pairs_are_tabled_and_a_pair_meeting_an_arm_at_home_is_left_to_the_cell() -> None:
    pairs = ArmPairs(_Cell(), FailureMemo())
    arms = ("north", "south", "west")
    per_move = [
        [_option("x", "x"), _option("x2", "x2")],
        [_option("y", "q")],
        [_option("bad", "w")],
    ]
    table = pairs.table(STEP, arms, per_move, POSES)
    assert isinstance(table, PairTable)
    assert table.why_not((0, 0, 0)) == AT_PICK  # north at x meets south at y
    assert table.why_not((1, 0, 0)) is None  # west's "bad" meets a home arm: not a pair's
    assert (0, 1, 2, 0) in table.at_pick


def test_a_meeting_at_the_targets_of_a_buffer_move_is_not_remembered() -> None:
    cell, memo = _Cell(), FailureMemo()
    pairs = ArmPairs(cell, memo)
    step = Step((Move("o1"), Move("o2", to_buffer=True)), "cycle", 2)
    per_move = [[_option("a", "x")], [_option("b", "y")]]
    assert pairs.table(step, ("north", "south"), per_move, POSES) == AT_PLACE
    assert len(memo) == 0
    goal_step = Step((Move("o1"), Move("o2")), "pair", 1)
    assert pairs.table(goal_step, ("north", "south"), per_move, POSES) == AT_PLACE
    assert len(memo) == 1


def test_the_grounder_reuses_a_meeting_across_assignments_and_decisions() -> None:
    path = DATA / "four_arm_cycle.yaml"
    instance = load_instance(path)
    r = rearrangement_problem(instance, WorldContext.load(instance.scene_path(path)))
    solver = SdarSolver(r.problem, SdarTaskPlanner(), SdarOptions(assignments=24))
    grounder = solver.grounder
    rotate = solver.planner.candidates(solver.view())[0]
    assert rotate.kind == "rotate" and len(rotate.moves) == 4
    combine = grounder.k.pairs.combine
    by_name = {solver.cache.show(a): a for a in grounder.home}
    meet = {by_name["north"], by_name["south"]}
    # two assignments that share north on the first move and south on the second
    first_two = (by_name["north"], by_name["south"])
    grounder._assignments = lambda step: [  # type: ignore[method-assign]
        (*first_two, by_name["east"], by_name["west"]),
        (*first_two, by_name["west"], by_name["east"]),
    ]
    homes = set(grounder.home.values())
    checks: list[Mapping[str, str]] = []

    def blocked(confs: Mapping[str, str]) -> str | None:  # north and south always meet
        checks.append(confs)
        active = {a for a, q in confs.items() if q not in homes}
        return None if meet <= active else combine(confs)

    grounder.k.pairs.combine = blocked
    assert grounder.select([rotate], MotionMode.FULL) == []  # both assignments use both
    first = len(checks)
    # found at the first assignment, recalled at the second: once per stage (2 and 6 options)
    assert grounder.k.memo.hits == 2
    assert any("the arms collide at the objects (remembered)" in r for r in solver.failures.reasons)
    # the next decision in the same arrangement: nothing checked in pairs again
    assert grounder.select([rotate], MotionMode.FULL) == []
    assert len(checks) == first


def test_the_neighbourhood_of_a_step_holds_its_objects_and_those_resting_near() -> None:
    where = {"pa": (0.0, 0.0), "ga": (1.0, 0.0), "pc": (0.1, 0.0), "pd": (0.5, 0.5)}
    where |= {"pe": (1.0, 0.15)}
    poses = {"a": "pa", "c": "pc", "d": "pd", "e": "pe"}
    found = neighbourhood(["a"], poses, {"a": "ga"}, where.get, 0.2)
    assert found == {"a": "pa", "c": "pc", "e": "pe"}  # c near its pose, e near its goal
    assert neighbourhood(["a"], {**poses, "d": "lost"}, {"a": "ga"}, where.get, 0.2) is None
    assert neighbourhood(["a"], poses, {"a": "lost"}, where.get, 0.2) is None


def test_a_step_no_arms_ground_is_skipped_until_an_object_near_it_moves(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    path = DATA / "four_arm_cycle.yaml"
    instance = load_instance(path)
    ctx = WorldContext.load(instance.scene_path(path))
    r = rearrangement_problem(instance, ctx)
    solver = SdarSolver(r.problem, SdarTaskPlanner(), SdarOptions(plane=table_plane(ctx)))
    grounder = solver.grounder
    rotate = solver.planner.candidates(solver.view())[0]
    grounded: list[tuple[str, ...]] = []

    def nothing(step: Step, arms: tuple[str, ...], mode: MotionMode) -> list[Grounding]:
        grounded.append(arms)
        return []

    monkeypatch.setattr(grounder, "_ground", nothing)
    assert grounder.select([rotate], MotionMode.FULL) == []
    tried = len(grounded)
    assert tried > 0
    assert grounder.select([rotate], MotionMode.FULL) == []  # the next decision: remembered
    assert len(grounded) == tried
    assert solver.failures.reasons[-1].endswith("no assignment of arms grounds it (remembered)")
    # one of its objects moves: tested again
    poses = solver.cache.current_poses()
    moved = {**poses, rotate.objects[0]: solver.goals[rotate.objects[0]]}
    monkeypatch.setattr(solver.cache, "current_poses", lambda: dict(moved))
    assert grounder.select([rotate], MotionMode.FULL) == []
    assert len(grounded) == 2 * tried
    # a step whose groundings were all tried before (tabu) is not remembered as failing
    monkeypatch.setattr(solver.cache, "current_poses", lambda: dict(poses))
    grounder.k.memo = grounder.k.pairs.memo = FailureMemo()

    def tabu(step: Step, arms: tuple[str, ...], mode: MotionMode) -> list[Grounding]:
        grounder._tabu_met = True
        return []

    monkeypatch.setattr(grounder, "_ground", tabu)
    assert grounder.select([rotate], MotionMode.FULL) == []
    assert len(grounder.k.memo) == 0


def test_grasps_for_objects_placed_at_once_are_searched_whatever_the_arms() -> None:
    targets = [("a", "ta"), ("b", "tb"), ("c", "tc")]
    # b's gripper with grasp b1 meets a at its goal; c's gripper meets b at its goal unless c2
    bad = {("b", "b1", "a"), ("c", "c1", "b")}

    def clear(o: str, p: str, g: str, o2: str, p2: str) -> bool:
        return (o, g, o2) not in bad

    assert grippers_can_clear(targets, [["a1"], ["b1", "b2"], ["c1", "c2"]], clear)
    assert not grippers_can_clear(targets, [["a1"], ["b1"], ["c1", "c2"]], clear)
    assert not grippers_can_clear(targets, [["a1"], ["b2"], ["c1"]], clear)
    assert grippers_can_clear([], [], clear)


def test_a_step_whose_grippers_always_meet_is_skipped_for_good(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    path = DATA / "four_arm_cycle.yaml"
    instance = load_instance(path)
    r = rearrangement_problem(instance, WorldContext.load(instance.scene_path(path)))
    solver = SdarSolver(r.problem, SdarTaskPlanner(), SdarOptions())
    grounder = solver.grounder
    rotate = solver.planner.candidates(solver.view())[0]
    cache = solver.cache
    asked: list[tuple[str, ...]] = []
    test = cache.test

    def never(stream: str, inputs: tuple[str, ...]) -> bool:
        if stream == cache.voc.grasp_cfree:
            asked.append(inputs)
            return False
        return test(stream, inputs)

    monkeypatch.setattr(cache, "test", never)
    monkeypatch.setattr(grounder, "_assignments", lambda step: pytest.fail("no arms needed"))
    assert grounder.select([rotate], MotionMode.FULL) == []
    assert solver.failures.reasons[-1].endswith(
        "keeps every gripper clear of the other objects at their goals"
    )
    n = len(asked)
    assert n > 0
    assert grounder.select([rotate], MotionMode.FULL) == []  # remembered: nothing asked
    assert len(asked) == n
    # a step of two moves is left to its stages (its swap stage searches more grasps)
    two = Step(rotate.moves[:2], "swap", 1)
    assert grounder.k.skip(two) is None
