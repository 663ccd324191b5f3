"""The dense family ``N``: mixed sizes packed at the paper's clearance, neighbours trading
places, the others turned on their spot; and the shipped ``dense`` suite."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.dense import DENSE_SIZES, neighbour_pairs
from sdar_tamp.world.dependency import instance_dependency_graph
from sdar_tamp.world.footprint import corners, inflate, overlap_matrix
from sdar_tamp.world.generators import FAMILIES, GeneratorOptions, generate_instance
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.suites import SUITES, load_suite, suite_members

GAP = GeneratorOptions().gap


def _poses(inst: Instance, which: str) -> np.ndarray:
    return np.array([getattr(o, which).as_tuple() for o in inst.objects])


def _sizes(inst: Instance) -> np.ndarray:
    return np.array([o.size[:2] for o in inst.objects])


def _two_cycles(inst: Instance) -> set[tuple[int, int]]:
    edges = set(instance_dependency_graph(inst).edges)
    return {(i, j) for i, j in edges if i < j and (j, i) in edges}


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_both_arrangements_keep_the_paper_clearance(seed: int) -> None:
    inst = generate_instance("N", 16, seed)
    for which in ("start", "goal"):
        grown = corners(_poses(inst, which), inflate(_sizes(inst), GAP / 2 - 1e-6))
        over = overlap_matrix(grown, grown)
        np.fill_diagonal(over, False)
        assert not over.any(), which


def test_sizes_are_mixed_and_graspable_and_pairs_share_one() -> None:
    inst = generate_instance("N", 20, 3)
    sizes = [o.size for o in inst.objects]
    assert set(sizes) <= set(DENSE_SIZES) and len(set(sizes)) >= 2
    assert all(sizes[2 * k] == sizes[2 * k + 1] for k in range(10))


def test_neighbours_trade_places_and_the_others_turn_on_their_spot() -> None:
    inst = generate_instance("N", 24, 7)
    starts, goals = _poses(inst, "start"), _poses(inst, "goal")
    swaps = _two_cycles(inst)
    assert len(swaps) >= 2
    d = np.linalg.norm(starts[:, None, :2] - starts[None, :, :2], axis=2)
    np.fill_diagonal(d, np.inf)
    for i, j in swaps:
        # the goal of each is the other's place, and they are neighbours: no object between
        assert np.allclose(goals[i, :2], starts[j, :2]) and np.allclose(goals[j, :2], starts[i, :2])
        assert d[i, j] <= np.sort(d[i])[2] + 1e-12
    others = [k for k in range(24) if not any(k in s for s in swaps)]
    assert others
    for k in others:
        assert np.allclose(goals[k, :2], starts[k, :2])
        assert not math.isclose(goals[k, 2], starts[k, 2])  # a new pose: picked and placed again


def test_the_table_is_packed_far_denser_than_random_placement() -> None:
    def spread(inst: Instance) -> float:
        p = _poses(inst, "start")[:, :2]
        return float(np.mean(np.linalg.norm(p - p.mean(axis=0), axis=1)))

    dense = generate_instance("N", 16, 0)
    random = generate_instance("R", 16, 0)
    assert spread(dense) < 0.8 * spread(random)


def test_same_seed_same_dense_instance_and_the_family_is_checked() -> None:
    assert generate_instance("N", 12, 4) == generate_instance("N", 12, 4)
    assert generate_instance("N", 12, 4) != generate_instance("N", 12, 5)
    assert "N" in FAMILIES
    with pytest.raises(ParameterError, match="family N needs at least 3"):
        generate_instance("N", 2, 0)


def test_neighbour_pairs_are_disjoint_consecutive_and_bounded() -> None:
    rng = np.random.default_rng(0)
    for n in (3, 8, 24):
        pairs = neighbour_pairs(n, rng)
        flat = [k for p in pairs for k in p]
        assert len(flat) == len(set(flat)) and all(j == i + 1 and i % 2 == 0 for i, j in pairs)
        assert 1 <= len(pairs) <= max(1, int(2 / 3 * n) // 2)


def test_the_dense_suite_is_shipped() -> None:
    # that its files are current (generated with the infeasibility proofs as the acceptance
    # test) is checked in tests/streams/test_feasibility.py
    assert "dense" in SUITES
    assert [m.name for m in suite_members("dense")] == ["N16", "N20", "N24"]
    assert [len(i.objects) for i in load_suite("dense")] == [16, 20, 24]


def test_the_command_line_names_every_family_and_suite() -> None:
    from sdar_tamp.cli.generate import CLI_FAMILIES, CLI_SUITES

    assert CLI_FAMILIES == FAMILIES and CLI_SUITES == SUITES
