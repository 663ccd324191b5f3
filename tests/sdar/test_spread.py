"""The finish's spread steps (several one-object moves at once, arms apart in the plane) and
the steps SDAR-T no longer proposes because their arms obviously meet."""

from __future__ import annotations

from typing import cast

from sdar_tamp.graph import DependencyGraph
from solvers.sdar.assignment import ArmAssigner
from solvers.sdar.cache import StreamCache
from solvers.sdar.k_steps import TaskScene, meets, rotations
from solvers.sdar.move_option import Option
from solvers.sdar.options import SdarOptions
from solvers.sdar.report import Failures
from solvers.sdar.spending import plane_seating, spread_steps
from solvers.sdar.tasks import Layout, Move, Step, TaskView

#: The bases of the four-arm test table (south, north, west, east).
BASES = ((0.0, -0.5), (0.0, 0.5), (-0.6, 0.0), (0.6, 0.0))


# -- the finish's spread steps -------------------------------------------------------------------

#: Four objects each in front of its own arm of the four-arm table (south, north, west, east).
APART = {
    "a": ((0.0, -0.3), (0.1, -0.3)),
    "b": ((0.0, 0.3), (0.1, 0.3)),
    "c": ((-0.4, 0.0), (-0.4, 0.1)),
    "d": ((0.4, 0.0), (0.4, 0.1)),
}


def _singles(*objs: str) -> list[Step]:
    return [Step((Move(o),), "single", 1) for o in objs]


def test_plane_seating_gives_each_object_the_nearest_free_arm() -> None:
    layout = Layout(APART, BASES)
    assert plane_seating(layout, [Move(o) for o in "abcd"]) == (0, 1, 2, 3)
    near_a = dict(APART, e=((0.05, -0.25), (0.1, -0.2)))
    # e's nearest arm (south) is a's: the next nearest free one
    assert plane_seating(Layout(near_a, BASES), [Move("a"), Move("e")])[1] != 0
    assert plane_seating(Layout(APART, BASES[:2]), [Move(o) for o in "abc"]) == (0, 1)
    # a buffer move is seated by its object's pose alone: f's goal is at the north arm
    far_goal = dict(APART, f=((0.0, -0.3), (0.0, 0.45)))
    assert plane_seating(Layout(far_goal, BASES), [Move("f")]) == (1,)
    assert plane_seating(Layout(far_goal, BASES), [Move("f", True)]) == (0,)


def test_the_finish_moves_objects_far_apart_with_their_nearest_arms_at_once() -> None:
    view = _layout_view(APART)
    singles = _singles("a", "b", "c", "d")
    steps = spread_steps(view, singles, 0.2)
    assert steps[0].objects == ("a", "b", "c", "d") and steps[0].kind == "spread"
    assert steps[0].rank == 1 and steps[1:] == singles
    assigner = ArmAssigner(
        cast(StreamCache, None), SdarOptions(), dict.fromkeys("snwe", "q"), cast(Failures, None),
        lambda *args: [],
    )  # fmt: skip
    assigner.by_plane = True  # arms sorted e, n, s, w: bases in that order
    sorted_bases = (BASES[3], BASES[1], BASES[0], BASES[2])
    layout = Layout(APART, sorted_bases)
    assert assigner.assignments(steps[0], layout) == [("s", "n", "w", "e")]


def test_the_finish_joins_no_object_near_another_arm_blocked_or_waiting() -> None:
    near_a = dict(APART, e=((0.05, -0.25), (0.1, -0.2)))
    assert spread_steps(_layout_view(near_a), _singles("a", "e", "b"), 0.2)[0].objects == (
        "a", "b", "c", "d",
    )  # fmt: skip
    names = tuple(sorted(APART))  # a's goal overlaps d's pose: a waits for d to leave
    blocked = _layout_view(APART, ((names.index("a"), names.index("d")),))
    # a is skipped at first; d joins after it (the other objects left come after the
    # singles), and with d lifted a's goal is free: a joins on the next pass (a chain)
    assert spread_steps(blocked, _singles("b", "a", "c"), 0.2)[0].objects == ("b", "c", "d", "a")
    # a's blocker e lies beside b, whose arm it would come too near: neither e nor a joins
    near_b = dict(APART, e=((0.05, 0.25), (-0.1, 0.2)))
    names = tuple(sorted(near_b))
    behind = _layout_view(near_b, ((names.index("a"), names.index("e")),))
    assert spread_steps(behind, _singles("b", "a", "c"), 0.2)[0].objects == ("b", "c", "d")
    graph = DependencyGraph(names, ())
    waiting = TaskView(graph, frozenset(), frozenset(), frozenset({("c", "a")}), 4,
                       Layout(APART, BASES))  # fmt: skip
    assert spread_steps(waiting, _singles("a", "c", "d"), 0.2)[0].objects == ("a", "d", "b")
    buffered = [Step((Move("a", True),), "buffer", 1), *_singles("b")]
    spread, goals, *rest = spread_steps(_layout_view(APART), buffered, 0.2)
    assert spread.moves == (Move("a", True), Move("b"), Move("c"), Move("d"))
    # next, in case a's nearest arm reaches no buffer: the goal moves alone, a's included
    assert goals.kind == "spread" and goals.moves == (Move("a"), Move("b"), Move("c"), Move("d"))
    assert rest == buffered


def test_the_finish_breaks_two_cycles_at_once_never_one_twice() -> None:
    names = tuple(sorted(APART))  # cycles a <-> b and c <-> d
    i = names.index
    edges = ((i("a"), i("b")), (i("b"), i("a")), (i("c"), i("d")), (i("d"), i("c")))
    view = _layout_view(APART, edges)
    breaks = [Step((Move(o, True),), "cycle", 2) for o in "abcd"]
    spread, *rest = spread_steps(view, breaks, 0.2)
    assert spread.moves == (Move("a", True), Move("c", True))
    assert rest == breaks  # no goal is free without a buffer move: no step of goal moves
    # with a lifted, b's goal is free: b joins a's buffer move if their arms stay apart
    chain = spread_steps(view, [breaks[0]], 0.2)[0]
    assert chain.moves[0] == Move("a", True) and Move("b", True) not in chain.moves


def test_without_layout_two_arms_or_gap_the_finish_keeps_its_single_steps() -> None:
    singles = _singles("a", "b")
    assert spread_steps(_layout_view(APART), singles, 0.0) == singles
    graph = DependencyGraph(tuple(sorted(APART)), ())
    two = TaskView(graph, frozenset(), frozenset(), arms=2, layout=Layout(APART, BASES[:2]))
    assert spread_steps(two, singles, 0.2) == singles
    bare = TaskView(graph, frozenset(), frozenset(), arms=4)
    assert spread_steps(bare, singles, 0.2) == singles


# -- SDAR-T: steps whose arms obviously meet -----------------------------------------------------


def _layout_view(places: dict[str, tuple[tuple[float, float], tuple[float, float]]],
                 edges: tuple[tuple[int, int], ...] = ()) -> TaskView:  # fmt: skip
    names = tuple(sorted(places))
    graph = DependencyGraph(names, edges)
    return TaskView(graph, frozenset(), frozenset(), arms=4, layout=Layout(places, BASES))


def test_a_step_whose_arms_cross_whatever_the_seating_is_not_proposed() -> None:
    # three objects crossing one point of the table: every seating on arms crosses there
    crossing = {
        "a": ((-0.15, -0.15), (0.15, 0.15)),
        "b": ((0.15, -0.15), (-0.15, 0.15)),
        "c": ((0.0, -0.2), (0.0, 0.2)),
    }
    assert meets(_layout_view(crossing), ("a", "b", "c"))
    apart = {
        "a": ((-0.2, -0.15), (-0.2, -0.05)),
        "b": ((0.2, 0.15), (0.2, 0.05)),
        "c": ((0.0, 0.2), (0.05, 0.2)),
    }
    assert not meets(_layout_view(apart), ("a", "b", "c"))
    assert not meets(_layout_view(crossing), ("a", "b"))  # two moves: left to SDAR-M
    no_layout = TaskView(DependencyGraph(("a", "b", "c"), ()), frozenset(), frozenset(), arms=4)
    assert not meets(no_layout, ("a", "b", "c"))


def test_a_rotation_whose_arms_cross_is_not_proposed_one_apart_is() -> None:
    # a 3-cycle a -> b -> c -> a: a's goal is b's start, and so on
    edges = ((0, 1), (1, 2), (2, 0))
    through = {  # a tight ring at the table's centre: every arm reaches into it
        "a": ((0.0, 0.0), (0.04, 0.0)),
        "b": ((0.04, 0.0), (0.02, 0.035)),
        "c": ((0.02, 0.035), (0.0, 0.0)),
    }
    view = _layout_view(through, edges)
    assert meets(view, ("a", "b", "c"))
    assert rotations(TaskScene(view), 4) == []
    # the test cells' 3-cycle (data/three_arm_cycle.yaml) is rotated by three arms
    ring = {
        "a": ((0.1, -0.15), (-0.1, -0.15)),
        "b": ((-0.1, -0.15), (0.0, 0.15)),
        "c": ((0.0, 0.15), (0.1, -0.15)),
    }
    kept = rotations(TaskScene(_layout_view(ring, edges)), 4)
    assert [step.objects for _, step in kept] == [("a", "b", "c")]


def test_the_finish_takes_a_one_move_steps_arms_by_plane_reach_without_ik() -> None:
    asked: list[str] = []

    def options(arm: str, *args: object) -> list[Option]:
        asked.append(arm)
        return []

    home = {"east": "q", "north": "q", "south": "q", "west": "q"}
    assigner = ArmAssigner(
        cast(StreamCache, None), SdarOptions(), home, cast(Failures, None), options
    )
    bases = ((0.6, 0.0), (0.0, 0.5), (0.0, -0.5), (-0.6, 0.0))  # sorted arms: e, n, s, w
    layout = Layout({"a": ((0.5, -0.1), (0.5, -0.2))}, bases)
    assigner.by_plane = True
    order = assigner.assignments(Step((Move("a"),), "single"), layout)
    assert order == [("east",), ("south",), ("north",), ("west",)]
    assert asked == []  # no IK asked to rank them


class _Reach:
    """A stream cache stand-in: every configuration one second from any other."""

    def current_arm_conf(self, arm: str) -> str:
        return f"q_{arm}"

    def arm_distance(self, a: str, b: str) -> float:
        return 1.0


def test_the_normal_search_asks_ik_of_the_nearest_arms_only_until_enough_reach() -> None:
    """A one-move step asks the arms by plane reach, nearest first, and stops once two reach
    (``moves + 1``); an arm that reaches nothing does not count. Without a layout every arm
    is asked."""
    asked: list[str] = []
    reach = {"east", "north", "south"}  # west reaches nothing

    def options(arm: str, move: Move, *args: object) -> list[Option]:
        asked.append(arm)
        return [Option("g", "pick", "t", "place")] if arm in reach else []

    home = {"east": "q", "north": "q", "south": "q", "west": "q"}
    assigner = ArmAssigner(
        cast(StreamCache, _Reach()), SdarOptions(), home, cast(Failures, None), options
    )
    bases = ((0.6, 0.0), (0.0, 0.5), (0.0, -0.5), (-0.6, 0.0))  # sorted arms: e, n, s, w
    layout = Layout({"a": ((-0.5, -0.1), (-0.5, -0.2))}, bases)  # nearest: w, s, n, e
    step = Step((Move("a"),), "single")
    costs = assigner.reach_costs(step, layout)
    assert asked == ["west", "south", "north"]
    assert set(costs) == {("south", 0), ("north", 0)}
    asked.clear()
    assert set(assigner.reach_costs(step)) == {(a, 0) for a in reach}
    assert asked == ["east", "north", "south", "west"]
