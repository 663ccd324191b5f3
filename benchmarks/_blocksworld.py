"""Seeded random blocksworld problems (4-operator domain in ``domains/blocksworld``)."""

from __future__ import annotations

import itertools
import random


def _random_towers(blocks: list[str], rng: random.Random) -> list[list[str]]:
    """Shuffle ``blocks`` and cut them into towers (bottom first)."""
    order = blocks[:]
    rng.shuffle(order)
    towers: list[list[str]] = []
    for block in order:
        if towers and rng.random() < 0.6:
            rng.choice(towers).append(block)
        else:
            towers.append([block])
    return towers


def blocksworld_problem(n_blocks: int, seed: int) -> str:
    """PDDL text of a random problem with ``n_blocks`` blocks; same seed, same problem."""
    if n_blocks < 1:
        raise ValueError(f"n_blocks must be >= 1; got {n_blocks}")
    rng = random.Random(seed)
    blocks = [f"b{i}" for i in range(1, n_blocks + 1)]
    init: list[str] = ["(hand-empty)"]
    for tower in _random_towers(blocks, rng):
        init.append(f"(on-table {tower[0]})")
        init.extend(f"(on {upper} {lower})" for lower, upper in itertools.pairwise(tower))
        init.append(f"(clear {tower[-1]})")
    goal: list[str] = []
    for tower in _random_towers(blocks, rng):
        goal.extend(f"(on {upper} {lower})" for lower, upper in itertools.pairwise(tower))
    if not goal:
        goal.append(f"(on-table {blocks[0]})")
    return (
        f"(define (problem bw-{n_blocks}-{seed})\n"
        "  (:domain blocksworld)\n"
        f"  (:objects {' '.join(blocks)})\n"
        f"  (:init {' '.join(init)})\n"
        f"  (:goal (and {' '.join(goal)})))\n"
    )
