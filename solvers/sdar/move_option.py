"""One way to do one move of a step: the grasp, the arm's configurations at both ends, the target
(SDAR-M's grounding combines one per move: :mod:`~solvers.sdar.grounding`)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Option:
    grasp: str
    pick: str  # arm configuration at the current pose
    target: str  # pose
    place: str  # arm configuration at the target
