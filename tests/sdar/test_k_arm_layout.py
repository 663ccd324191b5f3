"""Where objects and arms are (:class:`~solvers.sdar.tasks.Layout`): SDAR-T's extension of a step
and SDAR-M's assignment of arms with more than two arms."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import pytest

from sdar_tamp.app.problem import rearrangement_problem, table_plane
from sdar_tamp.graph import DependencyGraph
from sdar_tamp.world.instance import Pose2D, load_instance
from solvers.sdar.abstract import view_of
from solvers.sdar.k_steps import TaskScene, extend, extensions, merges
from solvers.sdar.options import SdarOptions
from solvers.sdar.sdar_t import SdarTaskPlanner
from solvers.sdar.solver import SdarSolver
from solvers.sdar.tasks import Layout, Move, Step, TaskView, _segment_gap
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
    assert layout.crosses(0, "a", 1, "b")  # north reaches over the table onto south's object
    assert not layout.crosses(0, "a", 2, "c")
    assert layout.arm_gap(0, "a", 1, "b") < 0.08 < 0.3 < layout.arm_gap(0, "a", 2, "c")
    assert layout.arm_gap(0, "a", 1, "b") == layout.arm_gap(1, "b", 0, "a")
    assert layout.conflicts([(0, "a"), (1, "b"), (2, "c")]) == 1
    assert layout.gap(["a"], ["b"]) < 0.08 < layout.gap(["a"], ["c"])


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


def test_assignments_whose_arms_cross_come_last() -> None:
    path = DATA / "four_arm_cycle.yaml"
    instance = load_instance(path)
    ctx = WorldContext.load(instance.scene_path(path))
    r = rearrangement_problem(instance, ctx)
    options = SdarOptions(plane=table_plane(ctx), assignments=24)
    solver = SdarSolver(r.problem, SdarTaskPlanner(), options)
    view = solver.view()
    solver.grounder.layout = view.layout
    assert view.layout is not None
    rotate = solver.planner.candidates(view)[0]
    found = solver.grounder._assignments(rotate)
    index = {a: k for k, a in enumerate(sorted(solver.home))}
    crossings = [
        view.layout.conflicts([(index[a], m.obj) for a, m in zip(arms, rotate.moves, strict=True)])
        for arms in found
    ]
    assert crossings == sorted(crossings) and crossings[0] < crossings[-1]


_Places = dict[str, tuple[tuple[float, float], tuple[float, float]]]


def _ring(cx: float, cy: float, names: str) -> _Places:
    """A tight 3-cycle at ``(cx, cy)``: each object's goal is the next one's pose."""
    pts = [(cx, cy), (cx + 0.04, cy), (cx + 0.02, cy + 0.035)]
    return {n: (pts[k], pts[(k + 1) % 3]) for k, n in enumerate(names)}


def _rings_view(places: _Places, arms: int) -> TaskView:
    names = tuple(sorted(places))
    i = names.index
    edges = tuple((i(x), i(y)) for x, y in ("ab", "bc", "ca", "de", "ef", "fd"))
    layout = Layout(places, BASES[:arms], clearance=0.08)
    return TaskView(DependencyGraph(names, edges), frozenset(), frozenset(), arms=arms,
                    layout=layout)  # fmt: skip


def test_two_cycle_breaks_far_apart_are_merged_into_one_step_of_four_arms() -> None:
    """Two tight 3-cycles (their rotations meet) on the south and north halves: with four arms
    the best step breaks both at once (two buffer moves, two goal moves); with three arms,
    or the cycles side by side, one at a time."""
    apart = {**_ring(-0.1, -0.3, "abc"), **_ring(0.1, 0.3, "def")}
    four = SdarTaskPlanner().candidates(_rings_view(apart, 4))
    best = four[0]
    assert len(best.moves) == 4 and sum(m.to_buffer for m in best.moves) == 2
    assert {best.objects[0], best.objects[1]} < set("abc") and set(best.objects[2:]) < set("def")
    merged = merges(TaskScene(_rings_view(apart, 4)), four, 4)
    assert merged and all(len(s.moves) == 4 for s in merged)
    assert all(len(s.moves) == 2 for s in SdarTaskPlanner().candidates(_rings_view(apart, 3))[:6])
    side_by_side = {**_ring(-0.05, -0.3, "abc"), **_ring(0.02, -0.3, "def")}
    view = _rings_view(side_by_side, 4)
    assert merges(TaskScene(view), SdarTaskPlanner().candidates(view), 4) == []
    one_cycle = {**_ring(-0.1, -0.3, "abc")}
    names = ("a", "b", "c")
    graph = DependencyGraph(names, ((0, 1), (1, 2), (2, 0)))
    lone = TaskView(graph, frozenset(), frozenset(), arms=4,
                    layout=Layout(one_cycle, BASES, clearance=0.08))  # fmt: skip
    assert merges(TaskScene(lone), SdarTaskPlanner().candidates(lone), 4) == []  # one component
