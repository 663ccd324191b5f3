"""The optimiser's rows and the checks with one to four arms placed around one table (the test
cells in ``data/``, fixtures in ``conftest.py``): arm-arm rows per pair of arms, the two-arm NLP
unchanged, the exact check of every pair of arms, feasibility proofs with one and three arms and
the grasp-blocking boxes of arms of one description."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D
from sdar_tamp.world.scene import Workspace
from streams.context import WorldContext
from streams.feasibility import prove_infeasible
from streams.finger_blocking import cell_gripper_boxes
from streams.motion.cartesian import tool_pose_ik
from streams.motion.nlp import build_nlp, parameter_layout
from streams.motion.optimiser import TrajectoryOptimiser
from streams.motion.optimiser_records import TrajOptOptions, TransferQuery
from streams.motion.slots import select_pairs
from streams.motion.sphere_pairs import HeldSpheres, arm_pairs, path_spheres
from streams.motion.waypoints import straight_line

SIZE = (0.08, 0.04, 0.05)
NO_OBSTACLES = (np.zeros((0, 3)), np.zeros(0))


# -- the optimiser's rows ---------------------------------------------------------------------


def test_arm_pairs() -> None:
    assert arm_pairs(1) == ()
    assert arm_pairs(2) == ((0, 1),)
    assert arm_pairs(3) == ((0, 1), (0, 2), (1, 2))
    assert len(arm_pairs(4)) == 6


@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_collision_rows_are_one_block_per_pair_of_arms(
    k: int, ctx: WorldContext, cells: dict[int, WorldContext]
) -> None:
    world = ctx if k == 2 else cells[k]
    o = TrajOptOptions(knots=4, arm_arm_slots=3, obstacle_slots=2, table_slots=1)
    built = build_nlp(world, o)
    pairs = k * (k - 1) // 2
    per_knot = pairs * o.arm_arm_slots + k * (o.obstacle_slots + o.table_slots)
    assert built.n_collision == (o.knots - 2) * per_knot
    lay = parameter_layout(world.layout, o, (6,) * k)
    aa_blocks = {name.split("_")[0] for name in lay.blocks if name.startswith("aa")}
    assert aa_blocks == {f"aa{p}" for p in range(pairs)}
    assert lay.size == built.layout.size


def test_two_arm_nlp_is_the_one_of_the_two_arm_planner(ctx: WorldContext) -> None:
    """The shipped cell's NLP (default options): rows, parameter vector and values at one
    random point as the two-arm optimiser gave them (sdar-tamp d551ef3)."""
    built = build_nlp(ctx, TrajOptOptions())
    rng = np.random.default_rng(0)
    x = rng.uniform(-1.0, 1.0, built.lbx.size)
    p = rng.uniform(-1.0, 1.0, built.layout.size)
    g = np.asarray(built.g_fn(x, p)).reshape(-1)
    jac = built.jac_g(x, p)[1]
    assert (built.n_collision, built.layout.size, g.size, int(jac.nnz())) == (480, 961, 684, 4392)
    np.testing.assert_allclose(g.sum(), 1052.7235945287946, rtol=1e-12)
    np.testing.assert_allclose(np.abs(g).sum(), 1441.0422096238715, rtol=1e-12)
    np.testing.assert_allclose(g[:3], [0.4552824871583925, 3.1748645028313334,
                                       -1.0515689864317477], rtol=1e-12)  # fmt: skip
    np.testing.assert_allclose(np.asarray(jac).sum(), -453.51022722167403, rtol=1e-12)


def test_pair_rows_measure_the_spheres_of_their_two_arms(cells: dict[int, WorldContext]) -> None:
    """Each pair block's rows are ``|c_i - c_j|^2 - (r_i + r_j + margin)^2`` of the sphere
    pairs chosen for it, at every interior knot (numeric sphere centres for comparison)."""
    ctx = cells[3]
    o = TrajOptOptions(knots=4, arm_arm_slots=4, obstacle_slots=2, table_slots=2,
                       select_distance=10.0, compiled=False)  # fmt: skip
    opt = TrajectoryOptimiser(ctx, o)
    q_a, q_b = ctx.scene.home, ctx.scene.home + 0.3
    held = tuple(HeldSpheres.empty() for _ in range(3))
    query = TransferQuery(q_a, q_b, held, NO_OBSTACLES, 3.0)
    path = straight_line(q_a, q_b, o.knots)
    spheres = path_spheres(ctx, path, held)
    selection = select_pairs(spheres, path_spheres(ctx, path[[0, -1]], held), query, o, None)
    p, _, _ = opt._parameters(query, selection)
    g = np.asarray(opt._g_fn(path[1:-1].reshape(-1), p)).reshape(-1)
    per_knot = opt._n_collision // (o.knots - 2)
    assert per_knot == 3 * 4 + 3 * (2 + 2)
    for knot in range(o.knots - 2):
        rows = g[knot * per_knot : (knot + 1) * per_knot]
        for pair, (i, j) in enumerate(arm_pairs(3)):
            chosen = selection.aa[pair]
            assert len(chosen) == o.arm_arm_slots  # select_distance: every slot filled
            ci = spheres.coarse_centres[i][knot + 1][chosen[:, 0]]
            cj = spheres.coarse_centres[j][knot + 1][chosen[:, 1]]
            r = spheres.coarse_radii[i][chosen[:, 0]] + spheres.coarse_radii[j][chosen[:, 1]]
            want = np.sum((ci - cj) ** 2, axis=1) - (r + o.margin) ** 2
            got = rows[pair * o.arm_arm_slots : (pair + 1) * o.arm_arm_slots]
            np.testing.assert_allclose(got, want, atol=1e-9)


# -- checks with any number of arms -----------------------------------------------------------


def test_the_exact_check_sees_every_pair_of_arms(cells: dict[int, WorldContext]) -> None:
    """Two arms meeting at the table centre collide whichever two of the four they are."""
    ctx = cells[4]
    world = ctx.new_world()
    reach: dict[str, np.ndarray] = {}
    for arm in ctx.arm_names:
        T = ctx.kinematics[arm].fk_tcp(ctx.home(arm))
        T[:3, 3] = (0.0, 0.0, 0.15)
        q = tool_pose_ik(ctx.kinematics[arm], T, ctx.home(arm))
        assert q is not None, arm
        reach[arm] = q
    for a, b in itertools.combinations(ctx.arm_names, 2):
        q = ctx.layout.join({**{x: ctx.home(x) for x in ctx.arm_names}, a: reach[a]})
        assert not world.in_collision(q)  # one arm alone at the centre
        q = ctx.layout.replace(q, b, reach[b])
        owners = {{p.first.split("_")[0], p.second.split("_")[0]} == {a, b}
                  for p in world.report(q)}  # fmt: skip
        assert world.in_collision(q) and True in owners, (a, b)


def test_feasibility_proofs_with_one_and_three_arms(cells: dict[int, WorldContext]) -> None:
    """An object beyond the one arm's reach is proven stuck in the one-arm cell and not in the
    three-arm cell (the north arm reaches it); a trio boxed in is stuck with any arm count."""
    ws = Workspace((-0.30, 0.30), (-0.25, 0.25))

    def instance(starts: list[Pose2D], goals: list[Pose2D]) -> Instance:
        pairs = enumerate(zip(starts, goals, strict=True))
        return Instance("k", ws, tuple(ObjectSpec(f"o{i}", SIZE, s, g) for i, (s, g) in pairs))

    far = instance([Pose2D(0.0, 0.35, 0.0)], [Pose2D(0.0, -0.1, 0.0)])
    proof = prove_infeasible(cells[1], far)
    assert proof is not None and proof.phase == "start"
    assert proof.lines()[1] == "o0: no grasp within reach of any arm"
    assert prove_infeasible(cells[3], far) is None
    trio = [Pose2D(0.0, -0.045, 0.0), Pose2D(0.0, 0.0, 0.0), Pose2D(0.0, 0.045, 0.0)]
    spread = [Pose2D(-0.15, -0.15, 0.0), Pose2D(0.0, -0.15, 0.0), Pose2D(0.15, -0.15, 0.0)]
    for k in (1, 3):
        boxed = prove_infeasible(cells[k], instance(trio, spread))
        assert boxed is not None and set(boxed.objects) == {"o0", "o1", "o2"}
        assert prove_infeasible(cells[k], instance(spread, trio[::-1])) is not None
        assert prove_infeasible(cells[k], instance(spread, spread[::-1])) is None


def test_grasp_blocking_boxes_of_arms_of_one_description(
    ctx: WorldContext, cells: dict[int, WorldContext]
) -> None:
    """Arms of one description and gripper count once, however many the cell has."""
    shipped = cell_gripper_boxes(ctx.scene)
    for k in (1, 3, 4):
        boxes = cell_gripper_boxes(cells[k].scene)
        assert len(boxes) == len(shipped) > 0
        for a, b in zip(boxes, shipped, strict=True):
            np.testing.assert_allclose(a.T_tcp_box, b.T_tcp_box)
