"""The counters of one stream planning solve, handed to users as ``Solution.statistics``."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class SearchStatistics:
    """What one solve counted and timed (updated as it runs).

    Attributes:
        iterations: passes of the search loop (one optimistic world and plan search each).
        skeletons: optimistic plans that needed stream calls.
        search_time: time spent in the classical planner [s] (grounding included).
        sample_time: time spent calling stream instances [s].
        grounding_time: the part of ``search_time`` the planner spent grounding each
            round's task (instantiating actions and axioms over the facts planned on) [s].
        world_time: time spent building the optimistic worlds planned on [s].
        complexity: the complexity level reached.
        time: the whole solve [s] (set at the end).
        facts: real facts known at the end (set at the end).
    """

    iterations: int = 0
    skeletons: int = 0
    search_time: float = 0.0
    sample_time: float = 0.0
    complexity: int = 0
    time: float = 0.0
    facts: int = 0
    grounding_time: float = 0.0
    world_time: float = 0.0

    def as_mapping(self) -> dict[str, float]:
        """The public form, ``Solution.statistics``: one entry per field, in field order."""
        return {
            "iterations": self.iterations,
            "skeletons": self.skeletons,
            "search_time": self.search_time,
            "sample_time": self.sample_time,
            "complexity": self.complexity,
            "time": self.time,
            "facts": self.facts,
            "grounding_time": self.grounding_time,
            "world_time": self.world_time,
        }
