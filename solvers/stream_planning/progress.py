"""What ``solve(verbose=True)`` prints about the stream planning search: one line per round and
the final counts, on standard output (looked up at each print, so a test that captures it
reads the lines). While a search runs, a terminal also shows what the search is doing, on a
line the next print overwrites; anything else (a file, a pipe, a log) gets the lines only.

A round line::

    round 3 level 2: new skeleton (6 actions, 4 stream results), calls +5 (12), facts +7 (40),
    0.021 s (world 0.004, grounding 0.006, search 0.009, sampling 0.001)

The parts in brackets are the round's shares of the solve's ``world_time``, ``grounding_time``,
``search_time`` (grounding excluded here) and ``sample_time`` (see ``Solution.statistics``).

Its outcome is one of: ``new skeleton``, ``plan met before``, ``no plan`` (the level rises),
``solved``, ``infeasible`` or what the round's policy did with the plan.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from solvers.solution import StreamStatistics

CLEAR_LINE = "\r\x1b[K"
#: the parts of a round's time its line gives (``phases`` of :meth:`RoundLog.begin`)
PHASES = ("world", "grounding", "search", "sampling")


@dataclass
class _Round:
    number: int
    level: int
    calls: int
    facts: int
    start: float
    phases: tuple[float, ...] = field(default=())


class RoundLog:
    """The round lines of one solve (``enabled=False``: prints nothing)."""

    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self._round: _Round | None = None
        self._live = False  # a transient line is on the terminal

    def begin(
        self, number: int, level: int, calls: int, facts: int, phases: Sequence[float] = ()
    ) -> None:
        """A round starts at complexity ``level`` with ``calls`` calls and ``facts`` facts;
        ``phases``: the solve's world, grounding, search and sampling times [s] so far."""
        if not self.enabled:
            return
        self._round = _Round(number, level, calls, facts, time.perf_counter(), tuple(phases))
        self._show(f"round {number} level {level}: searching...")

    def end(self, outcome: str, calls: int, facts: int, phases: Sequence[float] = ()) -> None:
        """The round that began last ended with ``outcome``; prints its line (with the
        round's share of each of ``phases``, given as at :meth:`begin`)."""
        current = self._round
        if not self.enabled or current is None:
            return
        self._round = None
        shares = ""
        if len(phases) == len(PHASES) == len(current.phases):
            shares = (
                " ("
                + ", ".join(
                    f"{name} {now - then:.3f}"
                    for name, now, then in zip(PHASES, phases, current.phases, strict=True)
                )
                + ")"
            )
        self._print(
            f"round {current.number} level {current.level}: {outcome}, "
            f"calls +{calls - current.calls} ({calls}), "
            f"facts +{facts - current.facts} ({facts}), "
            f"{time.perf_counter() - current.start:.3f} s{shares}"
        )

    def summary(
        self,
        algorithm: str,
        status: str,
        statistics: Mapping[str, float],
        streams: Mapping[str, StreamStatistics],
        diagnosis: Sequence[str],
    ) -> None:
        """The final counts: the search's, each stream's, and why no plan was found."""
        if not self.enabled:
            return
        self._print(
            f"{algorithm}: {status} after {int(statistics.get('iterations', 0))} round(s), "
            f"{int(statistics.get('skeletons', 0))} skeleton(s), "
            f"complexity {int(statistics.get('complexity', 0))}, "
            f"search {statistics.get('search_time', 0.0):.3f} s "
            f"(grounding {statistics.get('grounding_time', 0.0):.3f} s), "
            f"worlds {statistics.get('world_time', 0.0):.3f} s, "
            f"sampling {statistics.get('sample_time', 0.0):.3f} s, "
            f"total {statistics.get('time', 0.0):.3f} s"
        )
        for name in sorted(streams):
            s = streams[name]
            self._print(
                f"  {name}: {s.calls} call(s), {s.successes} success(es), "
                f"{s.outputs} output(s), {s.time:.3f} s"
            )
        for reason in diagnosis:
            self._print(f"  why: {reason}")

    def _show(self, text: str) -> None:
        out = sys.stdout
        if out.isatty():
            out.write(f"{CLEAR_LINE}{text}")
            out.flush()
            self._live = True

    def _print(self, line: str) -> None:
        out = sys.stdout
        if self._live:
            out.write(CLEAR_LINE)
            self._live = False
        print(line, file=out, flush=True)
