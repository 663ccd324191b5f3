"""Grounding failures SDAR-M remembers while the objects they depend on rest where they did.

A grounding of a step fails for reasons that often outlive the decision that found them: two
grippers that always meet at two goals, an assignment of arms whose arms meet at the objects
whatever the grasps. Re-testing them at every decision (and, for the reasons that do not depend
on the arms, once per assignment of arms) is wasted work, so :class:`FailureMemo` keeps each
failure with the part of the arrangement it depends on, its *world*: the poses of the objects
involved (object -> pose). A failure is recalled only while every object of its world rests at
the same pose; the first time one has moved (or been lifted) it is forgotten and the grounding
is tested again.

Two kinds of keys are used: a key without arms, for failures that hold whatever arms do the
moves (``("step", moves)`` in :mod:`~solvers.sdar.grounding`: no assignment of arms grounds a
step of goal moves; its world is :func:`neighbourhood`, the poses of the step's objects and of
the objects resting near their poses and goals), and keys with the arms, for failures of one
assignment (two arms that meet whatever their options, :mod:`~solvers.sdar.arm_pairs`; its world
the poses of the two objects). A world is an approximation: IK and buffers see every object on
the table, the world only the near ones, so a failure may outlive a change far away. Remembering
a failure only prunes candidates; a plan never depends on it being right (every executed step is
checked by the solver's state and the plan by the validator's replay).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable, Iterable, Mapping
from dataclasses import dataclass


@dataclass(frozen=True)
class Remembered:
    """A failure: why, and the poses (object, pose) it depends on."""

    reason: str
    world: frozenset[tuple[str, str]]


class FailureMemo:
    """Failures by key, each valid while its world holds (see the module docstring)."""

    def __init__(self) -> None:
        self._failures: dict[Hashable, Remembered] = {}
        self.hits = 0
        """Failures recalled instead of being tested again."""
        self.forgotten = 0
        """Failures forgotten because an object of their world had moved."""

    def __len__(self) -> int:
        return len(self._failures)

    def recall(self, key: Hashable, poses: Mapping[str, str]) -> str | None:
        """The reason of the failure remembered under ``key`` when every object of its world
        is still at its pose in ``poses`` (object -> current pose; an object missing from it
        is lifted); None otherwise (a failure whose world changed is forgotten)."""
        known = self._failures.get(key)
        if known is None:
            return None
        if any(poses.get(obj) != pose for obj, pose in known.world):
            del self._failures[key]
            self.forgotten += 1
            return None
        self.hits += 1
        return known.reason

    def remember(self, key: Hashable, reason: str, world: Mapping[str, str]) -> None:
        """Keep the failure ``reason`` under ``key`` while the objects of ``world`` (object ->
        pose) rest at those poses."""
        self._failures[key] = Remembered(reason, frozenset(world.items()))


def neighbourhood(
    objects: Iterable[str],
    poses: Mapping[str, str],
    goals: Mapping[str, str],
    locate: Callable[[str], tuple[float, float] | None],
    radius: float,
) -> dict[str, str] | None:
    """The poses (object -> pose) of ``objects`` and of every object resting within ``radius``
    [m] of a pose or a goal of one of them (``locate``: a pose's ``(x, y)``); None when a pose
    is not located."""
    mine = set(objects)
    spots: list[tuple[float, float]] = []
    for obj in mine:
        for pose in (poses.get(obj), goals.get(obj)):
            xy = None if pose is None else locate(pose)
            if pose is not None and xy is None:
                return None
            if xy is not None:
                spots.append(xy)
    world: dict[str, str] = {}
    for obj, pose in poses.items():
        xy = locate(pose)
        if xy is None:
            return None
        if obj in mine or any(math.dist(xy, spot) <= radius for spot in spots):
            world[obj] = pose
    return world
