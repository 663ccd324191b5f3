"""``--shard i/N``: one of N disjoint parts of a sweep, for batch schedulers.

Shard ``i`` of ``N`` (1 <= i <= N) takes the (instance, combination) pairs whose SHA-256 of
``"instance/combination"`` is ``i - 1`` modulo ``N``. The N shards together take every pair
exactly once, and a pair's shard depends on its names only: the same on every machine and in
every Python process, and unchanged when instances are added to or removed from the
selection (a resumed shard keeps its pairs). Each shard writes its own folder;
:mod:`sdar_tamp.evaluation.merge` joins them.
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass

from sdar_tamp.errors import ParameterError

_SPEC = re.compile(r"\s*(\d+)\s*/\s*(\d+)\s*")


@dataclass(frozen=True)
class Shard:
    """Shard ``index`` of ``count`` (1-based)."""

    index: int
    count: int

    def __post_init__(self) -> None:
        if self.count < 1:
            raise ParameterError(f"shard: N must be >= 1, got {self.count}")
        if not 1 <= self.index <= self.count:
            raise ParameterError(
                f"shard: i must be in 1..{self.count} for N = {self.count}, got {self.index}"
            )

    def __str__(self) -> str:
        return f"{self.index}/{self.count}"

    def takes(self, instance: str, combination: str) -> bool:
        """Whether the pair (``instance``, ``combination``) belongs to this shard."""
        return shard_of(instance, combination, self.count) == self.index


def shard_of(instance: str, combination: str, count: int) -> int:
    """The shard (1..``count``) of the pair."""
    digest = hashlib.sha256(f"{instance}/{combination}".encode()).digest()
    return int.from_bytes(digest[:8], "big") % count + 1


def parse_shard(text: str) -> Shard:
    """``"i/N"`` as a :class:`Shard`; raises :class:`ParameterError` for anything else."""
    match = _SPEC.fullmatch(text)
    if match is None:
        raise ParameterError(f"shard must be i/N with integers 1 <= i <= N, got {text!r}")
    return Shard(int(match.group(1)), int(match.group(2)))
