"""The records of an optimistic world (:mod:`.optimistic` builds them): placeholder names
(``#o<k>``, an output not sampled yet), :class:`OptResult` (what an external would certify on
some inputs) and :class:`OptimisticWorld` (the facts a round plans over and where they come
from)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from sdar_tamp.language.formula_model import Atom

PLACEHOLDER = "#o"


def is_placeholder(name: str) -> bool:
    return name.startswith(PLACEHOLDER)


@dataclass(frozen=True)
class OptResult:
    """An optimistic result: what ``external`` would certify on ``inputs``."""

    external: str
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    domain: tuple[Atom, ...]
    certified: tuple[Atom, ...]
    level: int
    kind: str  # "stream", "function", "predicate" or "rule"


@dataclass
class OptimisticWorld:
    facts: dict[Atom, int]
    provenance: dict[Atom, OptResult]
    numeric: dict[tuple[str, tuple[str, ...]], float]  # an OptimisticCosts with deferred ones
    placeholders: list[str] = field(default_factory=list)
    complete: bool = True  # no instance was left out for the limit or for being disabled
    # later calls of some instance were left out for the limit (see OptimisticBuilder._further):
    # no plan proves nothing unless the goal is not even relaxed-reachable
    more_calls: bool = False
    # the lowest level at which something left out for the limit would enter (inf: none)
    next_level: float = math.inf
    # the lowest level of a later call's outputs a build without them left out (inf: none):
    # above the limit, a build with them (``further``) would give the same world
    further_level: float = math.inf
