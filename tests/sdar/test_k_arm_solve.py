"""SDAR end to end on cells of one, three and four arms (test cells in ``data/cells``), and
the k-arm pieces of SDAR-M: the stream declaration, the grounding and its error paths."""

from __future__ import annotations

from pathlib import Path

import pytest

from sdar_tamp.app.cell_streams import declaration_for_arms, streams_for_arms
from sdar_tamp.app.pipeline import solve_instance
from sdar_tamp.app.problem import Rearrangement, rearrangement_problem
from sdar_tamp.errors import ParameterError
from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.errors import StreamDefinitionError
from sdar_tamp.language.sexpr import SList, read_sexpr
from sdar_tamp.language.streams import parse_stream_file
from sdar_tamp.resources import domain_file
from sdar_tamp.world.instance import load_instance
from solvers.sdar.attempts import MotionMode
from solvers.sdar.options import SdarOptions
from solvers.sdar.sdar_t import SdarTaskPlanner
from solvers.sdar.solver import SdarSolver
from solvers.sdar.tasks import Move, Step, TaskView
from streams.context import WorldContext
from streams.stream_map import make_stream_map

DATA = Path(__file__).parent / "data"
STREAMS = domain_file("dual_arm_rearrangement", "stream.pddl").read_text(encoding="utf-8")
DOMAIN = parse_domain(domain_file("dual_arm_rearrangement").read_text(encoding="utf-8"))


def _rearrangement(name: str) -> Rearrangement:
    path = DATA / name
    instance = load_instance(path)
    return rearrangement_problem(instance, WorldContext.load(instance.scene_path(path)))


# -- end to end ---------------------------------------------------------------------------------


def test_one_arm_solves_a_chain_one_object_at_a_time() -> None:
    outcome = solve_instance(DATA / "one_arm_chain.yaml", time_limit=60.0, execution="sync")
    assert outcome.success, outcome.diagnosis
    assert outcome.plan is not None
    events = [(e.arm, e.type, e.object) for e in outcome.plan.events]
    order = ["o2", "o1", "o0"]  # the chain from its free end
    assert events == [("south", t, o) for o in order for t in ("grasp", "release")]
    assert outcome.plan.metrics.actions == 3 and outcome.figures.buffer_moves == 0


def test_three_arms_rotate_a_three_cycle_without_a_buffer() -> None:
    outcome = solve_instance(DATA / "three_arm_cycle.yaml", time_limit=60.0, execution="sync")
    assert outcome.success, outcome.diagnosis
    assert outcome.plan is not None
    assert outcome.plan.metrics.actions == 3 and outcome.figures.buffer_moves == 0
    grasps = [e for e in outcome.plan.events if e.type == "grasp"]
    releases = [e for e in outcome.plan.events if e.type == "release"]
    assert len({e.t for e in grasps}) == 1 and len({e.t for e in releases}) == 1  # one instant
    assert {e.arm for e in grasps} == {"south", "north", "west"}
    assert max(e.t for e in grasps) < min(e.t for e in releases)  # all lifted, then placed


def test_four_arms_rotate_a_four_cycle_without_a_buffer() -> None:
    outcome = solve_instance(DATA / "four_arm_cycle.yaml", time_limit=60.0, execution="sync")
    assert outcome.success, outcome.diagnosis
    assert outcome.plan is not None
    assert outcome.plan.metrics.actions == 4 and outcome.figures.buffer_moves == 0
    assert len({e.arm for e in outcome.plan.events}) == 4


def test_a_three_arm_rotation_is_written_as_consecutive_gripper_actions() -> None:
    r = _rearrangement("three_arm_cycle.yaml")
    solver = SdarSolver(r.problem, SdarTaskPlanner(), SdarOptions(max_time=60.0))
    solution = solver.solve()
    assert solution.plan is not None
    names = [a.name for a in solution.plan]
    assert names == ["move", "pick", "pick", "pick", "move", "place", "place", "place"]
    assert [t.kind for t in solution.trace] == ["rotate"]


# -- the stream declaration for k arms ----------------------------------------------------------


def _combine(text: str) -> SList:
    root = read_sexpr(text)
    return next(
        item
        for item in root.items
        if isinstance(item, SList) and str(item.items[0]) == ":stream"
        if str(item.items[1]) == "combine-confs"
    )


@pytest.mark.parametrize("arms", [1, 2, 3, 4, 6])
def test_combine_confs_is_declared_for_the_cells_arms(arms: int) -> None:
    model = parse_stream_file(streams_for_arms(STREAMS, arms), DOMAIN)
    stream = next(s for s in model.streams if s.name == "combine-confs")
    assert stream.inputs == tuple(v for i in range(1, arms + 1) for v in (f"?a{i}", f"?q{i}"))
    assert [a.predicate for a in stream.domain] == ["confof"] * arms
    assert [a.predicate for a in stream.certified] == ["dualconf", *["confin"] * arms]
    others = [s for s in model.streams if s.name != "combine-confs"]
    assert others == [s for s in parse_stream_file(STREAMS, DOMAIN).streams if s in others]


def test_the_generated_two_arm_declaration_is_the_shipped_one() -> None:
    shipped = parse_stream_file(STREAMS, DOMAIN)
    node = _combine(STREAMS)
    start = STREAMS.index("(:stream combine-confs")
    end = STREAMS.index("(:stream plan-dual-motion\n")
    head = STREAMS[:start] + declaration_for_arms(node, 2) + "\n  "
    generated = parse_stream_file(head + STREAMS[end:], DOMAIN)
    assert generated.streams == shipped.streams
    assert streams_for_arms(STREAMS, 2) is STREAMS


@pytest.mark.parametrize(
    ("declaration", "message"),
    [
        ("(:stream combine-confs :inputs (?a1 ?q1 ?a2) :outputs (?d))", "two arms"),
        ("(:stream combine-confs :inputs (?a1 ?q1 ?b2 ?q2) :outputs (?d))", "ending in 2"),
        (
            "(:stream combine-confs :inputs (?a1 ?q1 ?a2 ?q2) "
            ":domain (and (confof ?a1 ?q2)) :outputs (?d))",
            "mixes",
        ),
        (
            "(:stream combine-confs :inputs (?a1 ?q1 ?a2 ?q2) "
            ":domain (and (confof ?a1 ?q1)) :outputs (?d))",
            "repeat the first",
        ),
    ],
)
def test_a_declaration_that_is_not_per_arm_is_a_located_error(
    declaration: str, message: str
) -> None:
    text = f"(define (stream s)\n  {declaration})"
    with pytest.raises(StreamDefinitionError, match=message) as info:
        streams_for_arms(text, 3)
    assert str(info.value).startswith("stream.pddl:2:3")


def test_bad_arm_counts_and_missing_streams_are_refused() -> None:
    with pytest.raises(ParameterError, match="arms must be >= 1"):
        streams_for_arms(STREAMS, 0)
    with pytest.raises(StreamDefinitionError, match="no stream 'combine-confs'"):
        streams_for_arms("(define (stream s))", 3)


def test_combine_confs_takes_one_pair_per_arm_of_the_cell() -> None:
    ctx = WorldContext.load(DATA / "cells" / "three_arms.yaml")
    combine = make_stream_map(ctx)["combine-confs"]
    r = _rearrangement("three_arm_cycle.yaml")
    home = {a.arm: a for a in r.home.arms}
    pairs = [x for a in ctx.arm_names for x in (a, home[a])]
    (conf,) = next(combine(*pairs))
    assert conf == r.home
    assert not list(combine(*pairs[:4]))  # an arm missing
    assert not list(combine(*pairs[:4], *pairs[:2]))  # an arm twice
    with pytest.raises(ParameterError, match="pairs"):
        list(combine(*pairs[:3]))
    with pytest.raises(ParameterError, match="its configuration"):
        list(combine("south", home["north"], *pairs[2:]))


# -- grounding and error paths ------------------------------------------------------------------


def test_three_moves_one_arm_at_a_time_keep_the_other_arms_at_home() -> None:
    r = _rearrangement("three_arm_cycle.yaml")
    solver = SdarSolver(r.problem, SdarTaskPlanner(), SdarOptions(one_arm_at_a_time=True))
    rotate = solver.planner.candidates(solver.view())[0]
    assert rotate.kind == "rotate"
    (first, *_) = solver.grounder.select([rotate], MotionMode.FULL)
    cache = solver.cache
    show = {name: cache.show(name) for name in rotate.objects}
    order = [(show[rotate.objects[e.index]], e.pick) for e in first.sequence]
    # o0's goal is where o1 rests, o1's where o2 rests, o2's where o0 rests: the first object
    # is held while the one whose goal it frees is picked and placed, and so on
    assert order == [
        ("o1", True), ("o0", True), ("o0", False), ("o2", True), ("o2", False), ("o1", False)
    ]  # fmt: skip
    for event in first.sequence:
        acting = first.arms[event.index]
        for d, arm, q in cache.state.atoms(cache.voc.confin):
            if d == event.conf and arm != acting:
                assert q == solver.home[arm]


class _TooMany:
    """A task planner that proposes three moves whatever the cell."""

    @property
    def name(self) -> str:
        return "too-many"

    def candidates(self, view: TaskView) -> list[Step]:
        return [Step(tuple(Move(x) for x in view.remaining[:3]), "pair")]

    def commit(self, step: Step, view: TaskView) -> None:
        raise AssertionError("never executed")


def test_a_step_of_more_moves_than_arms_is_an_error_of_the_task_planner() -> None:
    r = _rearrangement("one_arm_chain.yaml")
    solver = SdarSolver(r.problem, _TooMany(), SdarOptions(max_time=30.0))
    assert solver.view().arms == 1
    with pytest.raises(ParameterError, match=r"step of 3 moves .* for a cell of 1 arm"):
        solver.solve()


def test_a_move_no_arm_reaches_is_a_reason_of_the_dead_end(monkeypatch: pytest.MonkeyPatch) -> None:
    r = _rearrangement("three_arm_cycle.yaml")
    solver = SdarSolver(r.problem, SdarTaskPlanner(), SdarOptions())
    rotate = solver.planner.candidates(solver.view())[0]
    monkeypatch.setattr(solver.grounder, "_move_options", lambda *args, **kwargs: [])
    assert solver.grounder.select([rotate], MotionMode.FULL) == []
    (reason,) = solver.failures.reasons
    assert reason.startswith("rotate (") and "no arm has a grasp with IK at o" in reason


def test_assignments_with_more_than_two_arms_are_bounded_and_distinct() -> None:
    r = _rearrangement("four_arm_cycle.yaml")
    solver = SdarSolver(r.problem, SdarTaskPlanner(), SdarOptions(assignments=3))
    rotate = solver.planner.candidates(solver.view())[0]
    found = solver.grounder._assignments(rotate)
    assert 1 <= len(found) <= 3
    assert all(len(set(arms)) == len(rotate.moves) == 4 for arms in found)
