"""The optimiser's arm-arm slots follow each pair of arms' coarse sphere models."""

from __future__ import annotations

import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.cells import cell_path
from sdar_tamp.world.scene import load_scene
from streams.context import WorldContext
from streams.motion.nlp import build_nlp, pair_slot_counts, parameter_layout
from streams.motion.optimiser_records import TrajOptOptions, TransferQuery
from streams.motion.slots import select_pairs
from streams.motion.sphere_pairs import HeldSpheres, path_spheres
from streams.motion.spheres import arm_spheres, box_spheres
from streams.motion.waypoints import straight_line


def test_slots_per_pair_from_the_coarse_sphere_counts() -> None:
    o = TrajOptOptions()
    assert o.pair_slots((25, 25)) == (24,)  # two UR5e arms: the slots they always had
    assert o.pair_slots((25, 27)) == (24,)  # a UR5e and a UR10e
    assert o.pair_slots((35, 35)) == (33,)  # two Pandas
    assert o.pair_slots((25, 35)) == (28,)  # floor(0.96 * sqrt(25 * 35))
    assert o.pair_slots((25, 25, 35)) == (24, 28, 28)  # arm_pairs order: (0,1), (0,2), (1,2)
    assert o.pair_slots((25,)) == ()  # one arm: no pair
    assert TrajOptOptions(slots_per_sphere=2.0).pair_slots((25, 25)) == (50,)
    assert TrajOptOptions(slots_per_sphere=1e-3).pair_slots((25, 25)) == (1,)  # at least one


def test_a_set_slot_count_serves_every_pair() -> None:
    assert TrajOptOptions(arm_arm_slots=7).pair_slots((25, 43, 60)) == (7, 7, 7)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"arm_arm_slots": 0}, "arm_arm_slots must be at least 1"),
        ({"slots_per_sphere": 0.0}, "slots_per_sphere must be a finite number > 0"),
        ({"slots_per_sphere": float("nan")}, "slots_per_sphere must be a finite number > 0"),
        ({"slots_per_sphere": float("inf")}, "slots_per_sphere must be a finite number > 0"),
    ],
)
def test_bad_slot_options_are_refused(kwargs: dict[str, float], message: str) -> None:
    with pytest.raises(ParameterError, match=message):
        TrajOptOptions(**kwargs)  # type: ignore[arg-type]


def test_layout_and_selection_need_a_slot_count(ctx: WorldContext) -> None:
    o = TrajOptOptions()
    with pytest.raises(ParameterError, match="give pair_slots"):
        parameter_layout(ctx.layout, o)
    held = (HeldSpheres.empty(), HeldSpheres.empty())
    path = straight_line(ctx.scene.home, ctx.scene.home + 0.2, o.knots)
    spheres = path_spheres(ctx, path, held)
    query = TransferQuery(path[0], path[-1], held, (np.zeros((0, 3)), np.zeros(0)), 2.0)
    with pytest.raises(ParameterError, match="give pair_slots"):
        select_pairs(spheres, path_spheres(ctx, path[[0, -1]], held), query, o, None)


def test_the_ur5e_cell_keeps_24_slots_and_the_panda_cell_gets_33(ctx: WorldContext) -> None:
    o = TrajOptOptions(knots=4)
    assert pair_slot_counts(ctx, o) == (24,)
    panda = WorldContext.load(load_scene(cell_path("panda_facing")))
    assert [len(panda.fk[a].coarse.radius) for a in panda.arm_names] == [35, 35]
    built = build_nlp(panda, o)
    assert built.pair_slots == (33,)
    per_knot = 33 + 2 * (o.obstacle_slots + o.table_slots)
    assert built.n_collision == (o.knots - 2) * per_knot
    # every slot can be filled: a wide selection distance takes the 33 closest pairs
    wide = TrajOptOptions(knots=4, select_distance=10.0)
    held = (HeldSpheres.empty(), HeldSpheres.empty())
    home = panda.scene.home
    path = straight_line(home, home + 0.1, wide.knots)
    spheres = path_spheres(panda, path, held)
    query = TransferQuery(path[0], path[-1], held, (np.zeros((0, 3)), np.zeros(0)), 2.0)
    ends = path_spheres(panda, path[[0, -1]], held)
    chosen = select_pairs(spheres, ends, query, wide, None, built.pair_slots)
    assert chosen.aa[0].shape == (33, 2) and chosen.aa_lb[0].shape == (33,)


@pytest.mark.parametrize("half", [[0.027, 0.033, 0.012], [0.03, 0.045, 0.04], [0.2, 0.03, 0.03]])
def test_coarse_box_spheres_are_as_long_as_the_middle_side_and_cover(half: list[float]) -> None:
    h = np.array(half)
    c, r = box_spheres(h, coarse=True)
    fine_c, _ = box_spheres(h)
    assert len(r) <= len(fine_c)
    # cells about as long as the middle side, at most three per axis
    assert len(r) == int(np.prod(np.clip(np.ceil(h / (1.25 * np.median(h))), 1, 3)))
    pts = np.random.default_rng(3).uniform(-1, 1, (4000, 3)) * h
    corners = np.array(np.meshgrid(*[[-1, 1]] * 3)).reshape(3, -1).T * h
    pts = np.concatenate([pts, corners])
    gap = np.linalg.norm(pts[:, None] - c[None], axis=-1) - r[None]
    assert np.all(gap.min(axis=1) <= 1e-12)


def test_the_panda_coarse_model_has_one_sphere_per_small_box() -> None:
    """The Panda's link 5 and link 7 boxes get one coarse sphere each (were 4 and 6); the
    hand (joint 7) keeps its six-sphere box along the hand."""
    urdf = load_scene(cell_path("panda_facing")).arms[0].urdf
    coarse = arm_spheres(urdf, coarse=True)
    assert len(coarse) == 35
    assert np.bincount(coarse.joint).tolist() == [0, 5, 5, 4, 4, 6, 3, 8]


def test_the_slot_counts_are_part_of_the_compiled_code_key(ctx: WorldContext) -> None:
    """Two optimisers that differ only in their slot counts (same options, same code) have
    different recipes, so neither loads the other's compiled library."""
    from streams.motion.optimiser import TrajectoryOptimiser

    o = TrajOptOptions(knots=4, compiled=False)
    one = TrajectoryOptimiser(ctx, o)
    other = TrajectoryOptimiser(ctx, o)
    other.pair_slots = (25,)
    assert one.pair_slots == (24,)
    assert one.recipe() != other.recipe()
