"""How SDAR-M attempts groundings: which motion stream, and which groundings not to retry.

With a quick motion stream (no fallbacks), the groundings of the best rank are tried with it
first (:class:`QuickLadder`); a grounding that failed with the quick stream is not tried with
it again, one that failed with the full stream never again (:class:`TabuLists`).
"""

from __future__ import annotations

import enum
from collections.abc import Hashable
from dataclasses import dataclass


class MotionMode(enum.Enum):
    """Which motion stream an attempt uses: the quick one (no fallbacks) or the full one."""

    QUICK = "quick"
    FULL = "full"


class TabuLists:
    """Groundings that failed: with the full motion stream (never tried again) and with the
    quick one (not tried again with the quick stream)."""

    def __init__(self) -> None:
        self._full: set[Hashable] = set()
        self._quick: set[Hashable] = set()

    def blocked(self, key: Hashable, mode: MotionMode) -> bool:
        return key in self._full or (mode is MotionMode.QUICK and key in self._quick)

    def add(self, key: Hashable, mode: MotionMode) -> None:
        (self._quick if mode is MotionMode.QUICK else self._full).add(key)


@dataclass
class QuickLadder:
    """The groundings of the best rank tried with the quick motion stream first: ``left``
    attempts remain; ``best_rank`` is the rank of the first grounding found with it."""

    left: int
    best_rank: int | None = None

    @property
    def mode(self) -> MotionMode:
        return MotionMode.QUICK if self.left > 0 else MotionMode.FULL
