"""ArmFK generated from the chain of a 7-DoF arm: against pinocchio (1e-9), its derivatives
against finite differences, its spheres on the chain's frames."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.world.errors import KinematicsError
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene
from streams.context import WorldContext
from streams.motion._casadi import ca, function, sx_sym, to_array
from streams.motion.fk_casadi import ArmFK
from streams.motion.optimiser import TrajectoryOptimiser
from streams.motion.optimiser_records import TrajOptOptions, TransferQuery
from streams.motion.slots import Selection, select_pairs
from streams.motion.sphere_pairs import HeldSpheres, path_spheres
from streams.motion.waypoints import straight_line
from tests.kinematics.conftest import ARM7_URDF

LINKS = tuple(f"link{i}" for i in range(1, 8))


@pytest.mark.parametrize("arm", ["left", "right"])
def test_chain_fk_equals_pinocchio(ctx7: WorldContext, arm: str) -> None:
    fk, kin = ctx7.fk[arm], ctx7.kinematics[arm]
    assert fk.chain is not None and fk.params is None
    assert fk.dof == 7 and fk.n_frames == 8 and fk.held_frame == 7
    q_sym = sx_sym("q", 7)
    frames = function("frames", [q_sym], fk.frames(q_sym))
    rng = np.random.default_rng(1)
    for q in rng.uniform(kin.spec.lower_array, kin.spec.upper_array, (20, 7)):
        np.testing.assert_allclose(fk.tcp(q), kin.fk_tcp(q), atol=1e-9)
        np.testing.assert_allclose(fk.tool0(q), kin.fk_tool0(q), atol=1e-9)
        out = frames(q)
        for link, T in zip((*LINKS, "tool0"), out, strict=True):
            np.testing.assert_allclose(to_array(T), kin.fk(q, link), atol=1e-9)


def test_sphere_centres_follow_their_links(ctx7: WorldContext) -> None:
    fk, kin = ctx7.fk["left"], ctx7.kinematics["left"]
    assert set(np.unique(fk.spheres.joint)) == set(range(1, 8))
    q = np.random.default_rng(2).uniform(kin.spec.lower_array, kin.spec.upper_array, (3, 7))
    centres = fk.centres(q)
    assert centres.shape == (3, len(fk.spheres), 3)
    for k in range(3):
        for i, (j, c) in enumerate(zip(fk.spheres.joint, fk.spheres.centre, strict=True)):
            T = kin.fk(q[k], LINKS[int(j) - 1])
            np.testing.assert_allclose(centres[k, i], T[:3, :3] @ c + T[:3, 3], atol=1e-9)
    assert fk.centres(q, coarse=True).shape == (3, len(fk.coarse), 3)
    np.testing.assert_allclose(
        fk.tcp_positions(q), np.stack([kin.fk_tcp(x)[:3, 3] for x in q]), atol=1e-9
    )


def test_derivatives_match_finite_differences(ctx7: WorldContext) -> None:
    fk = ctx7.fk["left"]
    q_sym = sx_sym("q", 7)
    frames = fk.frames(q_sym)
    out = ca.vertcat(ca.vec(frames[-1][:3, :]), ca.vec(fk.centres_fn(q_sym)))
    f = function("f", [q_sym], [out])
    jac = function("J", [q_sym], [ca.jacobian(out, q_sym)])
    rng = np.random.default_rng(3)
    h = 1e-6
    for q in rng.uniform(-1.5, 1.5, (5, 7)):
        J = to_array(jac(q))
        fd = np.stack(
            [
                (to_array(f(q + h * e)) - to_array(f(q - h * e))).ravel() / (2 * h)
                for e in np.eye(7)
            ],
            axis=1,
        )
        np.testing.assert_allclose(J, fd, atol=1e-7)


def test_the_ur_arm_keeps_its_dh_form(ctx: WorldContext) -> None:
    fk = ctx.fk["left"]
    assert fk.chain is None and fk.params is not None and fk.n_frames == 6 and fk.dof == 6
    assert fk.recipe().startswith("URParameters(")


def test_recipe_names_the_chain(ctx7: WorldContext) -> None:
    recipe = ctx7.fk["left"].recipe()
    assert recipe.startswith("tool0|") and "joint7:revolute" in recipe


def test_shapes_off_the_chain_are_refused(scene7: Scene, tmp_path: Path) -> None:
    text = ARM7_URDF.read_text(encoding="utf-8").replace(
        '<joint name="gripper_left_finger_joint" type="fixed">',
        '<joint name="gripper_left_finger_joint" type="prismatic">\n'
        '    <axis xyz="0 1 0"/><limit lower="0" upper="0.04" effort="1" velocity="1"/>',
    )
    path = tmp_path / "fingers.urdf"
    path.write_text(text, encoding="utf-8")
    kin = ArmKinematics.from_model(scene7.arm("left"), path, tcp_offset=0.1034)
    with pytest.raises(KinematicsError, match=r"gripper_left_finger_joint.*not on the chain"):
        ArmFK.from_kinematics(kin)


def test_slots_of_a_chain_arm_hang_on_its_joint_frames(
    ctx7: WorldContext, ctx: WorldContext
) -> None:
    """The optimiser's slots choose among the seven joint frames (not the tool frame too): a
    held object's spheres, given in the tool frame, hang on the last joint frame, and every
    arm-arm and table row equals the numeric clearance of its spheres at every knot."""
    fk = ctx7.fk["left"]
    assert len(fk.joint_frames(sx_sym("q", 7))) == 7 == fk.dof and fk.n_frames == 8
    assert fk.T_last_tool is not None and ctx.fk["left"].T_last_tool is None
    o = TrajOptOptions(knots=4, arm_arm_slots=5, obstacle_slots=1, table_slots=3,
                       select_distance=10.0, compiled=False)  # fmt: skip
    opt = TrajectoryOptimiser(ctx7, o)
    assert opt._lay.blocks["aa0_frame0"][1] == (5, 7)
    held = (HeldSpheres(np.array([[0.01, 0.02, 0.15], [-0.02, 0.0, 0.12]]), np.array([0.03, 0.02])),
            HeldSpheres(np.array([[0.0, -0.01, 0.14]]), np.array([0.025])))  # fmt: skip
    q_a = ctx7.scene.home
    q_b = q_a + np.random.default_rng(4).uniform(-0.4, 0.4, q_a.size)
    query = TransferQuery(q_a, q_b, held, (np.zeros((0, 3)), np.zeros(0)), 3.0)
    path = straight_line(q_a, q_b, o.knots)
    spheres = path_spheres(ctx7, path, held)
    na, nb = len(fk.coarse), len(ctx7.fk["right"].coarse)  # the held spheres follow these
    none, empty = np.zeros(0), np.zeros((0, 2), dtype=np.int64)
    forced = Selection((np.array([[na, nb], [na + 1, 0], [3, nb]]),), (empty, empty),
                       (np.array([len(fk.spheres) + 1]), np.array([len(fk.spheres)])),
                       (none,), (none, none), (none, none))  # fmt: skip
    sel = select_pairs(spheres, path_spheres(ctx7, path[[0, -1]], held), query, o, forced)
    assert sel.aa[0][:3].tolist() == [[na, nb], [na + 1, 0], [3, nb]]
    p, _, _ = opt._parameters(query, sel)
    g = np.asarray(opt._g_fn(path[1:-1].reshape(-1), p)).reshape(-1)
    per_knot = opt._n_collision // (o.knots - 2)
    for knot in range(o.knots - 2):
        rows = g[knot * per_knot : (knot + 1) * per_knot]
        ci = spheres.coarse_centres[0][knot + 1][sel.aa[0][:, 0]]
        cj = spheres.coarse_centres[1][knot + 1][sel.aa[0][:, 1]]
        r = spheres.coarse_radii[0][sel.aa[0][:, 0]] + spheres.coarse_radii[1][sel.aa[0][:, 1]]
        want = np.sum((ci - cj) ** 2, axis=1) - (r + o.margin) ** 2
        np.testing.assert_allclose(rows[: o.arm_arm_slots], want, atol=1e-9)
        start = o.arm_arm_slots + 2 * o.obstacle_slots
        for arm in range(2):
            idx = sel.table[arm]
            c = spheres.centres[arm][knot + 1][idx]
            want_t = c[:, 2] - spheres.radii[arm][idx] - o.margin
            got = rows[start + arm * o.table_slots : start + (arm + 1) * o.table_slots]
            np.testing.assert_allclose(got[: len(idx)], want_t, atol=1e-9)
