"""Execution of a grounding: plan its motions, then apply the domain's actions.

Every motion of a grounding is planned, in the state it starts from, before any action is
applied, so a failed grounding leaves nothing in the plan. Applied actions are checked
against the domain's lifted preconditions (:class:`~solvers.sdar.state.LiftedState`).

Gripper actions at one configuration: one gripper is a ``pick`` / ``place``, two are a
``pick-both`` / ``place-both`` (the two-arm swap's), three or more are consecutive ``pick`` /
``place`` actions with no ``move`` between (one instant and one dwell on the plan's timeline;
each placement's precondition then sees the objects placed before it, whose clearance is
certified for every ordered pair).
"""

from __future__ import annotations

import time
from collections.abc import Sequence

from sdar_tamp.language.formula_model import Atom
from solvers.sdar.attempts import MotionMode
from solvers.sdar.cache import StreamCache
from solvers.sdar.grounding import Grounding
from solvers.sdar.report import Failures, TaskRecord


class Executor:
    """Applies groundings to the state of ``cache``; holds the plan built so far, its cost
    and the time spent in the motion streams."""

    def __init__(self, cache: StreamCache, failures: Failures) -> None:
        self.cache = cache
        self.failures = failures
        self.plan: list[tuple[str, tuple[str, ...]]] = []
        self.cost = 0.0
        self.motion_time = 0.0  # [s]

    def execute(self, g: Grounding, record: TaskRecord, mode: MotionMode) -> bool:
        """Plan the transfer (in the state after the pick), then the approach; apply both
        only when both exist, so a failed candidate leaves nothing in the plan."""
        cache, voc = self.cache, self.cache.voc
        start_poses = [cache.current_poses()[o] for o in g.step.objects]
        targets = [o.target for o in g.options]
        self._certify_placements(g, targets)
        if not self._placeable(g, targets):
            self.failures.why(g.step, g.arms, "a target is not clear of the resting objects")
            return False
        if g.sequence:
            return self._execute_one_arm(g, record, mode)
        held = [
            Atom(voc.holding, (arm, move.obj, option.grasp))
            for arm, move, option in zip(g.arms, g.step.moves, g.options, strict=True)
        ]
        lifted = frozenset(g.step.objects)
        after_pick = tuple(sorted((*cache.fluents(voc.atpose, without=lifted), *held), key=str))
        t2 = self._motion(g.d_pick, g.d_place, record, after_pick, mode)
        if t2 is None:
            self.failures.why(g.step, g.arms, "no motion to the targets")
            return False
        d0 = cache.current_dualconf()
        if d0 != g.d_pick:
            fluents = cache.fluents(voc.atpose, voc.holding)
            t1 = self._motion(d0, g.d_pick, record, fluents, mode)
            if t1 is None:
                self.failures.why(g.step, g.arms, "no motion to the objects")
                return False
            self.apply(voc.move, d0, t1, g.d_pick)
            record.motions += 1
        self._gripper("pick", g, start_poses, [o.pick for o in g.options], g.d_pick)
        self.apply(voc.move, g.d_pick, t2, g.d_place)
        record.motions += 1
        self._gripper("place", g, targets, [o.place for o in g.options], g.d_place)
        return True

    def _execute_one_arm(self, g: Grounding, record: TaskRecord, mode: MotionMode) -> bool:
        """Execute ``g.sequence``: before each gripper action one motion brings the acting arm
        to its configuration and the other home, one arm at a time (the motion stream's
        planner moves them in turn). Every motion is planned, in the state it starts from,
        before any action is applied."""
        cache, voc = self.cache, self.cache.voc
        poses = cache.current_poses()
        held: dict[str, tuple[str, str]] = {}  # arm -> (object, grasp)
        d = cache.current_dualconf()
        actions: list[tuple[str, tuple[str, ...]]] = []
        for event in g.sequence:
            k = event.index
            arm, move, option = g.arms[k], g.step.moves[k], g.options[k]
            if d != event.conf:
                fluents = tuple(sorted(
                    [Atom(voc.atpose, (o, p)) for o, p in poses.items()]
                    + [Atom(voc.holding, (a, o, grasp)) for a, (o, grasp) in held.items()],
                    key=str,
                ))  # fmt: skip
                t = self._motion(d, event.conf, record, fluents, mode)
                if t is None:
                    reason = f"no one-arm motion for {cache.show(arm)}"
                    self.failures.why(g.step, g.arms, reason)
                    return False
                actions.append((voc.move, (d, t, event.conf)))
                d = event.conf
            if event.pick:
                pose = poses.pop(move.obj)
                held[arm] = (move.obj, option.grasp)
                actions.append((voc.pick, (arm, move.obj, pose, option.grasp, option.pick, d)))
            else:
                for other, pose in poses.items():  # certify what the placement needs
                    cache.test(voc.cfree, (move.obj, option.target, other, pose))
                poses[move.obj] = option.target
                del held[arm]
                actions.append(
                    (voc.place, (arm, move.obj, option.target, option.grasp, option.place, d))
                )
        for name, args in actions:
            self.apply(name, *args)
            if name == voc.move:
                record.motions += 1
        return True

    def _motion(
        self, d1: str, d2: str, record: TaskRecord, fluents: tuple[Atom, ...], mode: MotionMode
    ) -> str | None:
        voc = self.cache.voc
        start = time.perf_counter()
        stream = voc.quick_motion if mode is MotionMode.QUICK else voc.motion
        out = self.cache.outputs(stream, (d1, d2), 1, fluents)
        elapsed = time.perf_counter() - start
        self.motion_time += elapsed
        if out:
            record.motion_times.append(elapsed)
        return out[0][0] if out else None

    def apply(self, name: str, *args: str) -> None:
        self.cost += self.cache.state.apply(name, args)
        self.plan.append((name, args))

    def _gripper(
        self, which: str, g: Grounding, poses: Sequence[str], confs: Sequence[str], d: str
    ) -> None:
        voc = self.cache.voc
        parts = [
            (arm, move.obj, pose, option.grasp, conf)
            for arm, move, option, pose, conf in zip(
                g.arms, g.step.moves, g.options, poses, confs, strict=True
            )
        ]
        single = voc.pick if which == "pick" else voc.place
        both = voc.pick_both if which == "pick" else voc.place_both
        if len(parts) == 2:
            self.apply(both, d, *parts[0], *parts[1])
            return
        for arm, obj, pose, grasp, conf in parts:  # one, or more grippers at one instant
            self.apply(single, arm, obj, pose, grasp, conf, d)

    def _certify_placements(self, g: Grounding, targets: Sequence[str]) -> None:
        cfree = self.cache.voc.cfree
        resting = self.cache.current_poses()
        placed = list(zip(g.step.objects, targets, strict=True))
        for obj, target in placed:
            for other, pose in resting.items():
                self.cache.test(cfree, (obj, target, other, pose))
        for a, b in _placed_pairs(placed):
            self.cache.test(cfree, (*a, *b))

    def _placeable(self, g: Grounding, targets: Sequence[str]) -> bool:
        """Every target is certified clear of the objects resting after the pick (and of the
        other targets)."""
        cache = self.cache
        lifted = set(g.step.objects)
        resting = {o: p for o, p in cache.current_poses().items() if o not in lifted}
        placed = list(zip(g.step.objects, targets, strict=True))
        cfree = cache.streams[cache.voc.cfree].declaration.certified[0].predicate
        clear = all(
            cache.state.has(cfree, obj, t, other, p)
            for obj, t in placed
            for other, p in resting.items()
        )
        return clear and all(cache.state.has(cfree, *a, *b) for a, b in _placed_pairs(placed))


def _placed_pairs(
    placed: Sequence[tuple[str, str]],
) -> list[tuple[tuple[str, str], tuple[str, str]]]:
    """The (object, target) pairs whose clearance placing them at once needs: for two objects
    the one ``place-both`` requires; for more, placed one after another at one instant, every
    ordered pair (each placement sees the ones before it resting)."""
    if len(placed) == 2:
        return [(placed[0], placed[1])]
    return [(a, b) for a in placed for b in placed if a is not b]
