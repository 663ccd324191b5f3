"""Where objects and arms are (:class:`~solvers.sdar.tasks.Layout`): SDAR-T's extension of a step
and SDAR-M's assignment of arms with more than two arms."""

from __future__ import annotations

import dataclasses
import itertools
import math
from pathlib import Path

import pytest

from sdar_tamp.app.problem import rearrangement_problem, table_plane
from sdar_tamp.graph import DependencyGraph
from sdar_tamp.world.instance import Pose2D, load_instance
from solvers.sdar.abstract import view_of
from solvers.sdar.k_steps import TaskScene, extend, extensions
from solvers.sdar.options import SdarOptions
from solvers.sdar.sdar_t import SdarTaskPlanner
from solvers.sdar.solver import SdarSolver
from solvers.sdar.tasks import (
    LIKELY,
    MAX_ASSIGNMENTS,
    MEETING,
    Layout,
    Move,
    Step,
    TaskView,
    _meeting,
    _segment_gap,
)
from streams.context import WorldContext

DATA = Path(__file__).parent / "data"
#: The bases of the four-arm table (south, north, west, east).
BASES = ((0.0, -0.55), (0.0, 0.55), (-0.7, 0.0), (0.7, 0.0))


def _view(
    places: dict[str, tuple[tuple[float, float], tuple[float, float]]], arms: int
) -> TaskView:
    names = tuple(sorted(places))
    layout = Layout(places, BASES[:arms], clearance=0.08)
    return TaskView(DependencyGraph(names, ()), frozenset(), frozenset(), arms=arms, layout=layout)


def test_segment_gaps() -> None:
    assert _segment_gap((0, 0), (1, 1), (0, 1), (1, 0)) == 0.0  # they cross
    assert _segment_gap((0, 0), (1, 0), (0, 0.3), (1, 0.3)) == pytest.approx(0.3)
    assert _segment_gap((0, 0), (1, 0), (2, 0.5), (3, 0.5)) == pytest.approx(math.hypot(1, 0.5))
    assert _segment_gap((0, 0), (0, 0), (0, 1), (0, 2)) == pytest.approx(1.0)  # a point


def test_arms_reaching_across_each_other_cross_and_arms_on_their_own_side_do_not() -> None:
    places = {
        "a": ((0.05, -0.15), (0.10, -0.20)),  # south of the centre
        "b": ((0.08, -0.10), (0.05, -0.18)),  # beside it
        "c": ((-0.25, 0.05), (-0.28, -0.05)),  # west
    }
    layout = _view(places, 4).layout
    assert layout is not None
    assert layout.side("a") == 0 and layout.side("c") == 2
    assert layout.meet(0, "a", 1, "b") > 0.9  # north reaches over the table onto south's object
    assert layout.meet(0, "a", 2, "c") == 0.0  # far apart
    assert layout.arm_gap(0, "a", 1, "b") < 0.06 < 0.3 < layout.arm_gap(0, "a", 2, "c")
    both = layout.chance([(0, "a"), (1, "b"), (2, "c")])
    pairs = [(0, "a", 1, "b"), (0, "a", 2, "c"), (1, "b", 2, "c")]
    assert both == pytest.approx(math.prod(1 - layout.meet(*p) for p in pairs))
    assert layout.best_chance(["a", "c"]) == 1.0
    assert layout.best_chance(["a", "b"]) < LIKELY  # neighbours: any two arms meet
    assert layout.best_chance(["a", "b", "c", "a2", "x"]) == 0.0  # more objects than arms
    assert layout.gap(["a"], ["b"]) < 0.08 < layout.gap(["a"], ["c"])


def test_objects_apart_are_compared_pick_with_pick_and_goal_with_goal() -> None:
    places = {
        "a": ((0.0, 0.0), (0.3, 0.0)),
        "b": ((0.3, 0.0), (0.0, 0.2)),  # on a's goal now: a chain, not neighbours
        "c": ((0.0, 0.05), (0.6, 0.0)),  # beside a's pose
    }
    layout = Layout(places, BASES)
    assert layout.apart(["b"], ["a"]) == pytest.approx(0.3)  # the poses (goals: 0.36)
    assert layout.gap(["b"], ["a"]) == 0.0  # any pose or goal with any
    assert layout.apart(["c"], ["a", "b"]) == pytest.approx(0.05)
    assert layout.apart([], ["a"]) == math.inf


def test_the_chance_of_meeting_follows_the_measured_table() -> None:
    assert _meeting(0.0) == MEETING[0][1] and _meeting(1.0) == 0.0
    assert _meeting(0.08) == pytest.approx((0.71 + 0.58) / 2)
    gaps = [k / 100 for k in range(40)]
    assert all(_meeting(a) >= _meeting(b) for a, b in itertools.pairwise(gaps))


def test_the_best_chance_seats_objects_greedily_beyond_the_assignments_compared() -> None:
    bases = tuple((math.cos(k), math.sin(k)) for k in range(8))  # 8 arms on a unit circle
    places = {f"o{k}": ((0.5 * x, 0.5 * y), (0.5 * x, 0.5 * y)) for k, (x, y) in enumerate(bases)}
    layout = Layout(places, bases)
    objs = [f"o{k}" for k in range(5)]  # 8 * 7 * 6 * 5 * 4 = 6720 assignments: greedy
    assert math.perm(8, 5) > MAX_ASSIGNMENTS
    assert layout.best_chance(objs) == 1.0  # each on the arm behind it: far apart


def test_the_extension_adds_an_object_another_arm_reaches_apart_not_a_neighbour() -> None:
    places = {
        "o0": ((0.05, -0.15), (0.10, -0.20)),
        "o1": ((0.08, -0.10), (0.05, -0.18)),  # beside o0: first by object order
        "o2": ((-0.25, 0.05), (-0.28, -0.05)),  # west, apart
    }
    view = _view(places, 3)
    scene = TaskScene(view)
    step = Step((Move("o0"),), "single")
    blind = extend(scene, step, 2, spatial=False)
    assert blind.objects == ("o0", "o1")  # by dependencies (and object order) alone
    assert extend(scene, step, 2).objects == ("o0", "o2")
    three = extend(scene, step, 3)
    assert three.objects == ("o0", "o2")  # o1 crosses both arms left: not added
    assert [s.objects for s in extensions(scene, step, 3)] == [("o0", "o2"), ("o0", "o1", "o2")]


def test_without_a_layout_the_extension_is_by_dependencies_only() -> None:
    g = DependencyGraph(("o0", "o1", "o2"), ())
    view = view_of(g, frozenset(), frozenset(), arms=3)
    scene = TaskScene(view)
    step = Step((Move("o0"),), "single")
    assert [s.objects for s in extensions(scene, step, 3)] == [("o0", "o1", "o2")]
    assert extend(scene, step, 3).objects == extend(scene, step, 3, spatial=False).objects


def test_sdar_t_ranks_the_spatial_extension_before_the_blind_one() -> None:
    places = {
        "o0": ((0.05, -0.15), (0.10, -0.20)),
        "o1": ((0.08, -0.10), (0.05, -0.18)),
        "o2": ((-0.25, 0.05), (-0.28, -0.05)),
        "o3": ((0.25, 0.02), (0.28, -0.02)),  # east, apart
    }
    candidates = SdarTaskPlanner().candidates(_view(places, 4))
    first = candidates[0]
    assert len(first.moves) >= 3 and "o1" not in first.objects[2:]


def test_bad_layouts_are_refused() -> None:
    with pytest.raises(ValueError, match="at least one arm base"):
        Layout({}, ())
    with pytest.raises(ValueError, match="clearance >= 0"):
        Layout({}, BASES, clearance=-0.1)


def test_the_app_builds_the_plane_of_the_cell_and_the_solver_a_layout_beyond_two_arms() -> None:
    path = DATA / "four_arm_cycle.yaml"
    instance = load_instance(path)
    ctx = WorldContext.load(instance.scene_path(path))
    plane = table_plane(ctx)
    # the test cell's bases (tests/sdar/data/cells/four_arms.yaml)
    cell = ((0.0, -0.5), (0.0, 0.5), (-0.6, 0.0), (0.6, 0.0))
    assert plane.bases == dict(zip(("south", "north", "west", "east"), cell, strict=True))
    assert plane.locate(Pose2D(0.1, -0.2, 0.3)) == (0.1, -0.2)
    assert plane.locate("south") is None
    r = rearrangement_problem(instance, ctx)
    solver = SdarSolver(r.problem, SdarTaskPlanner(), SdarOptions(plane=plane))
    view = solver.view()
    assert view.layout is not None and set(view.layout.places) == set(view.remaining)
    assert sorted(view.layout.bases) == sorted(cell)
    assert SdarSolver(r.problem, SdarTaskPlanner(), SdarOptions()).view().layout is None
    # a plane that locates nothing gives no layout
    blind = dataclasses.replace(plane, locate=lambda value: None)
    assert SdarSolver(r.problem, SdarTaskPlanner(), SdarOptions(plane=blind)).view().layout is None


def test_only_the_assignments_likeliest_to_keep_the_arms_apart_are_grounded() -> None:
    path = DATA / "four_arm_cycle.yaml"
    instance = load_instance(path)
    ctx = WorldContext.load(instance.scene_path(path))
    r = rearrangement_problem(instance, ctx)
    options = SdarOptions(plane=table_plane(ctx), assignments=24)
    solver = SdarSolver(r.problem, SdarTaskPlanner(), options)
    view = solver.view()
    solver.grounder.layout = view.layout
    layout = view.layout
    assert layout is not None
    rotate = next(s for s in solver.planner.candidates(view) if s.kind == "rotate")
    found = solver.grounder._assignments(rotate)
    index = {a: k for k, a in enumerate(sorted(solver.home))}

    def chance(arms: tuple[str, ...]) -> float:
        return layout.chance([(index[a], m.obj) for a, m in zip(arms, rotate.moves, strict=True)])

    every = list(itertools.permutations(sorted(solver.home), len(rotate.moves)))
    best = max(map(chance, every))
    assert found and all(chance(arms) >= best / 2 for arms in found)
    assert len(found) < len(every)  # some assignments make two arms meet
