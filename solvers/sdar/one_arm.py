"""The order of the gripper actions of a step done one arm at a time (the baseline motion
planner, ``SdarOptions.one_arm_at_a_time``): each placement finds its target free, the other
arms waiting at home (:class:`~solvers.sdar.grounding.Grounder` builds the events)."""

from __future__ import annotations

from collections.abc import Sequence

from solvers.sdar.cache import StreamCache
from solvers.sdar.tasks import Step


def one_arm_order(cache: StreamCache, step: Step, targets: Sequence[str]) -> list[tuple[int, bool]]:
    """``(move index, pick?)`` in execution order. A move whose target is clear of every
    other resting object goes first, alone, then the other; otherwise (a swap) the first
    arm picks and waits at home holding its object while the second arm works. More than
    two moves: :func:`_one_arm_order_k`."""
    if len(step.moves) == 1:
        return [(0, True), (0, False)]
    if len(step.moves) > 2:
        return _one_arm_order_k(cache, step, targets)
    current = cache.current_poses()
    for k, (obj, target) in enumerate(zip(step.objects, targets, strict=True)):
        if all(
            cache.test(cache.voc.cfree, (obj, target, other, pose))
            for other, pose in current.items()
            if other != obj
        ):
            return [(k, True), (k, False), (1 - k, True), (1 - k, False)]
    return [(0, True), (1, True), (1, False), (0, False)]


def _one_arm_order_k(
    cache: StreamCache, step: Step, targets: Sequence[str]
) -> list[tuple[int, bool]]:
    """One arm at a time for a step of more than two moves: a held object whose target is
    clear of the resting objects is placed (the last picked first); else an object whose
    target is clear is picked (to be placed next); else the first object left is picked
    and held (its arm waits at home holding it); when nothing held can be placed and
    nothing is left to pick, the last picked is placed anyway (the placement check of the
    execution then refuses the grounding)."""
    cfree = cache.voc.cfree
    resting = dict(cache.current_poses())

    def clear(k: int) -> bool:
        obj = step.objects[k]
        return all(
            cache.test(cfree, (obj, targets[k], other, pose))
            for other, pose in resting.items()
            if other != obj
        )

    order: list[tuple[int, bool]] = []
    todo = list(range(len(step.moves)))
    held: list[int] = []
    while todo or held:
        place = next((k for k in reversed(held) if clear(k)), None)
        if place is None and not todo:
            place = held[-1]
        if place is not None:
            held.remove(place)
            resting[step.objects[place]] = targets[place]
            order.append((place, False))
            continue
        pick = next((k for k in todo if clear(k)), todo[0])
        todo.remove(pick)
        resting.pop(step.objects[pick])
        held.append(pick)
        order.append((pick, True))
    return order
