"""SDAR-M's choices by expected execution time: the placement configuration (one-arm time
from the pick plus the next motion's expected extra), and candidates the task planner holds
alike (``Step.tie``) compared by estimated motion time."""

from __future__ import annotations

import math
from collections.abc import Hashable, Sequence

from sdar_tamp.graph import DependencyGraph
from sdar_tamp.language.formula_model import Atom
from solvers.sdar.abstract import view_of
from solvers.sdar.attempts import MotionMode, TabuLists
from solvers.sdar.budget import Deadline
from solvers.sdar.grounding import Grounder, Grounding
from solvers.sdar.options import SdarOptions
from solvers.sdar.report import Failures
from solvers.sdar.sdar_t import SdarTaskPlanner
from solvers.sdar.tasks import Move, Step
from solvers.sdar.vocabulary import SdarVocabulary


class FakeCache:
    """The little of a stream cache that choosing a placement reads: IK outputs by target,
    and one-arm time estimates from tables."""

    def __init__(
        self,
        places: Sequence[str],
        times: dict[tuple[str, str], float],
        next_extra: dict[str, float],
        estimates: bool = True,
    ) -> None:
        self.voc = SdarVocabulary()
        self.places = list(places)
        self.times = times
        self.next_extra = next_extra
        self.functions: dict[str, object] = (
            {self.voc.arm_distance: None, self.voc.next_motion: None} if estimates else {}
        )
        self.limits: list[int] = []

    def outputs(
        self, stream: str, inputs: tuple[str, ...], limit: int, fluents: tuple[Atom, ...] = ()
    ) -> list[tuple[str, ...]]:
        assert stream == self.voc.ik
        self.limits.append(limit)
        return [(q,) for q in self.places[:limit]]

    def arm_distance(self, q1: str, q2: str) -> float:
        return self.times[q1, q2]

    def next_motion(self, q: str) -> float:
        return self.next_extra.get(q, 0.0)


def grounder(cache: object, options: SdarOptions | None = None) -> Grounder:
    return Grounder(
        cache,  # type: ignore[arg-type]
        options or SdarOptions(),
        {},
        {"left": "hl", "right": "hr"},
        TabuLists(),
        Failures(str),
        Deadline(math.inf),
    )


TIMES = {("pick", "qa"): 1.0, ("pick", "qb"): 0.4, ("pick", "qc"): 0.5}


def test_the_placement_reached_soonest_counting_the_next_motion_is_chosen() -> None:
    cache = FakeCache(["qa", "qb", "qc"], TIMES, {"qb": 0.3})
    place = grounder(cache)._place("left", "o1", "p", "g", "pick", ())
    assert place == "qc"  # 0.5 + 0 beats qb's 0.4 + 0.3 and qa's 1.0
    assert cache.limits == [SdarOptions().place_branches]
    cache = FakeCache(["qa", "qb", "qc"], TIMES, {})
    assert grounder(cache)._place("left", "o1", "p", "g", "pick", ()) == "qb"


def test_without_estimates_or_branches_the_streams_first_placement_stays() -> None:
    cache = FakeCache(["qa", "qb", "qc"], TIMES, {}, estimates=False)
    assert grounder(cache)._place("left", "o1", "p", "g", "pick", ()) == "qa"
    assert cache.limits == [1]  # only the first is asked for
    one = SdarOptions(place_branches=1)
    cache = FakeCache(["qa", "qb", "qc"], TIMES, {})
    assert grounder(cache, one)._place("left", "o1", "p", "g", "pick", ()) == "qa"
    assert grounder(FakeCache([], TIMES, {}))._place("left", "o", "p", "g", "pick", ()) is None


class CannedGrounder(Grounder):
    """Groundings by table (step objects -> estimates); records which steps were grounded."""

    def __init__(self, estimates: dict[tuple[str, ...], list[float]], options: SdarOptions):
        super().__init__(
            FakeCache([], {}, {}),  # type: ignore[arg-type]
            options,
            {},
            {"left": "hl", "right": "hr"},
            TabuLists(),
            Failures(str),
            Deadline(math.inf),
        )
        self.estimates = estimates
        self.grounded: list[tuple[str, ...]] = []

    def _assignments(self, step: Step) -> list[tuple[str, ...]]:
        return [("left", "right")[: len(step.moves)]]

    def _ground(self, step: Step, arms: tuple[str, ...], mode: MotionMode) -> list[Grounding]:
        self.grounded.append(step.objects)
        return [
            Grounding(step, arms, (), "d1", "d2", e) for e in self.estimates.get(step.objects, [])
        ]

    def key(self, step: Step, arms: tuple[str, ...], combo: tuple[object, ...]) -> Hashable:
        return (step.moves, arms, combo)


def pair(a: str, b: str, tie: tuple[int, ...] | None) -> Step:
    return Step((Move(a), Move(b)), "pair", 1, tie)


def test_candidates_alike_to_the_task_planner_are_compared_by_estimated_time() -> None:
    steps = [pair("a", "b", (0, 0)), pair("c", "d", (0, 0)), pair("e", "f", (0, 0)),
             pair("g", "h", (-1, 0)), pair("i", "j", (0, 0))]  # fmt: skip
    estimates = {s.objects: [3.0 + k, 4.0 + k, 5.0 + k] for k, s in enumerate(steps)}
    estimates["e", "f"] = [1.5, 9.0, 9.0]
    chosen = CannedGrounder(estimates, SdarOptions(peer_steps=4))
    found = chosen.select(steps, MotionMode.QUICK)
    assert found[0].step.objects == ("e", "f") and found[0].estimate == 1.5
    # grounded: the first, then its peers up to the first candidate of another tie
    assert chosen.grounded == [("a", "b"), ("c", "d"), ("e", "f")]
    capped = CannedGrounder(estimates, SdarOptions(peer_steps=1))
    assert capped.select(steps, MotionMode.QUICK)[0].step.objects == ("a", "b")
    assert capped.grounded == [("a", "b"), ("c", "d")]


def test_candidates_without_a_tie_keep_the_task_planners_order() -> None:
    steps = [pair("a", "b", None), pair("c", "d", None)]
    estimates = {("a", "b"): [5.0, 6.0, 7.0], ("c", "d"): [1.0]}
    chosen = CannedGrounder(estimates, SdarOptions(peer_steps=4))
    assert chosen.select(steps, MotionMode.QUICK)[0].step.objects == ("a", "b")
    assert chosen.grounded == [("a", "b")]
    assert not pair("a", "b", None).peer_of(pair("a", "b", None))
    assert pair("a", "b", (0,)).peer_of(pair("c", "d", (0,)))
    assert not pair("a", "b", (0,)).peer_of(Step((Move("c"), Move("d")), "pair", 2, (0,)))


def test_sdar_t_ties_candidates_that_differ_only_in_object_order() -> None:
    # o0 -> o1: o0's goal is blocked by o1, so pairs lifting o1 (without o0) free o0
    view = view_of(DependencyGraph(("o0", "o1", "o2", "o3"), ((0, 1),)), frozenset(), frozenset())
    steps = SdarTaskPlanner().candidates(view)
    pairs = {s.objects: s for s in steps if s.rank == 1}
    assert list(pairs) == [("o1", "o2"), ("o1", "o3"), ("o0", "o1"), ("o2", "o3")]
    assert pairs["o1", "o2"].tie == pairs["o1", "o3"].tie == (-1, -1)  # one freed, one edge
    assert pairs["o0", "o1"].tie == pairs["o2", "o3"].tie == (0, 0)
    assert pairs["o1", "o2"].peer_of(pairs["o1", "o3"])
    assert not pairs["o1", "o2"].peer_of(pairs["o0", "o1"])
    singles = {s.objects[0]: s.tie for s in steps if s.kind == "single"}
    assert singles == {"o1": (-1,), "o2": (0,), "o3": (0,)}  # by predecessors
    buffers = [s for s in steps if s.kind == "buffer"]
    assert buffers and all(s.tie is None for s in buffers)  # the planner's order stands
