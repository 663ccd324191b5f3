"""The numeric IK's compiled descent (:mod:`sdar_tamp.world.ik_kernel`) against the numpy
descent: the same poses solved, every solution on its pose and within the limits, a target's
solutions independent of its batch; joints of every kind; numpy where numba cannot run."""

from __future__ import annotations

import logging
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.world import ik_kernel
from sdar_tamp.world._pin import PinRobot, chain_to
from sdar_tamp.world.numeric_ik import (
    NumericIKOptions,
    chain_fk,
    numeric_ik,
    numeric_ik_branches,
    numeric_ik_from,
    pose_error,
)
from tests.world.test_numeric_ik import seven_dof

needs_kernel = pytest.mark.skipif(ik_kernel.kernel() is None, reason="numba cannot run here")
OPTS = NumericIKOptions(seeds=8, iterations=30, rounds=4, null_space_fade=0.003)


def _targets(chain: object, home: np.ndarray, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    _, T = chain_fk(chain, home + rng.uniform(-0.8, 0.8, (n, len(home))))  # type: ignore[arg-type]
    return T


@needs_kernel
def test_the_kernel_solves_what_numpy_solves(tmp_path: Path) -> None:
    _, chain = seven_dof(tmp_path)
    lo, hi = np.full(7, -2.8), np.full(7, 2.8)
    home = np.array([0.0, -0.5, 0.0, -2.0, 0.0, 1.5, 0.8])
    T = _targets(chain, home, 60, 2)
    runs = {}
    for compiled in (False, True):
        opts = replace(OPTS, compiled=compiled)
        runs[compiled] = numeric_ik_branches(chain, T, lo, hi, home, 4, opts, seed=1)
    (q_np, ok_np), (q_k, ok_k) = runs[False], runs[True]
    assert ok_k[:, 0].sum() >= ok_np[:, 0].sum() - 1 >= 57, (ok_k[:, 0].sum(), ok_np[:, 0].sum())
    for q, ok in ((q_np, ok_np), (q_k, ok_k)):
        for b in range(4):
            _, end = chain_fk(chain, q[:, b])
            err = np.abs(pose_error(T, end))[ok[:, b]]
            assert err.max() < 1e-6
            assert np.all((q[ok] >= lo - 1e-12) & (q[ok] <= hi + 1e-12))
    # as near the home as numpy's nearest solutions
    both = ok_np[:, 0] & ok_k[:, 0]
    near_k = np.linalg.norm(q_k[both, 0] - home, axis=1).mean()
    near_np = np.linalg.norm(q_np[both, 0] - home, axis=1).mean()
    assert near_k < near_np + 0.1, (near_k, near_np)


@needs_kernel
def test_a_target_gets_the_same_solutions_alone_or_in_a_batch(tmp_path: Path) -> None:
    _, chain = seven_dof(tmp_path)
    lo, hi = np.full(7, -2.8), np.full(7, 2.8)
    home = np.array([0.0, -0.5, 0.0, -2.0, 0.0, 1.5, 0.8])
    T = _targets(chain, home, 12, 3)
    q_all, ok_all = numeric_ik_branches(chain, T, lo, hi, home, 4, OPTS, seed=4)
    q_one, ok_one = numeric_ik_branches(chain, T[7:8], lo, hi, home, 4, OPTS, seed=4)
    np.testing.assert_array_equal(ok_one[0], ok_all[7])
    np.testing.assert_array_equal(q_one[0], q_all[7])


def _mixed_chain(tmp_path: Path) -> tuple[PinRobot, object]:
    """Four joints: about z, about an unaligned axis, along x (prismatic), about -y."""
    joints = [
        ("revolute", "0 0 0.3", "0 0 1"),
        ("revolute", "0 0.1 0.2", "0.6 0 0.8"),
        ("prismatic", "0.2 0 0", "1 0 0"),
        ("revolute", "0 0 0.25", "0 -1 0"),
    ]
    body = "".join(
        f'<joint name="j{i}" type="{kind}"><parent link="l{i}"/><child link="l{i + 1}"/>'
        f'<origin xyz="{xyz}" rpy="0.1 0 0"/><axis xyz="{axis}"/>'
        f'<limit lower="-1.5" upper="1.5" effort="1" velocity="1"/></joint><link name="l{i + 1}"/>'
        for i, (kind, xyz, axis) in enumerate(joints)
    )
    path = tmp_path / "mixed.urdf"
    path.write_text(f'<robot name="m"><link name="l0"/>{body}</robot>', "utf-8")
    robot = PinRobot.load(path)
    return robot, chain_to(robot, "l4")


@needs_kernel
def test_the_kernel_descends_on_every_joint_kind(tmp_path: Path) -> None:
    """Prismatic, unaligned and negative axes: the kernel's FK is the chain's (a start at the
    target converges at once, a start nearby reaches it)."""
    _, chain = _mixed_chain(tmp_path)
    packed = ik_kernel.pack(chain)  # type: ignore[arg-type]
    assert list(packed[2]) == [2, 0, 1, 0]
    rng = np.random.default_rng(6)
    q = rng.uniform(-1.0, 1.0, (20, 4))
    frames, end = chain_fk(chain, q)  # type: ignore[arg-type]
    k_frames, k_end = np.empty((4, 4, 4)), np.empty((4, 4))
    for i in range(20):
        ik_kernel._fk(packed, q[i], k_frames, k_end)
        np.testing.assert_allclose(k_end, end[i], atol=1e-12)
        np.testing.assert_allclose(k_frames, frames[i], atol=1e-12)
    lo, hi = np.full(4, -1.5), np.full(4, 1.5)
    opts = NumericIKOptions(position_tolerance=1e-9, rotation_tolerance=1e-9, iterations=100)
    # a 4-joint chain reaches a 4-dimensional set of poses: solve poses of that set from nearby
    q_from, done = numeric_ik_from(chain, end, lo, hi, (q + 0.05)[:, None], opts)  # type: ignore[arg-type]
    assert done.all()
    _, reached = chain_fk(chain, q_from[:, 0])  # type: ignore[arg-type]
    np.testing.assert_allclose(reached, end, atol=1e-7)


def test_without_numba_the_numeric_ik_descends_with_numpy(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    _, chain = seven_dof(tmp_path)
    lo, hi = np.full(7, -2.8), np.full(7, 2.8)
    home = np.array([0.0, -0.5, 0.0, -2.0, 0.0, 1.5, 0.8])
    T = _targets(chain, home, 8, 7)
    monkeypatch.setattr(ik_kernel, "_loaded", [])
    monkeypatch.setattr(ik_kernel.importlib.util, "find_spec", lambda name: None)
    with caplog.at_level(logging.INFO, logger="sdar_tamp.world.ik_kernel"):
        assert ik_kernel.kernel() is None
    assert "numba is not installed" in caplog.text
    result = numeric_ik(chain, T, lo, hi, q_ref=home, options=OPTS)
    assert result.ok.all()


def test_a_numba_that_cannot_compile_leaves_numpy(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    numba = pytest.importorskip("numba")

    def broken(**_: object) -> object:
        raise RuntimeError("llvmlite: cannot load")

    monkeypatch.setattr(ik_kernel, "_loaded", [])
    monkeypatch.setattr(numba, "njit", broken)
    with caplog.at_level(logging.WARNING, logger="sdar_tamp.world.ik_kernel"):
        assert ik_kernel.kernel() is None
    assert "numba cannot run the numeric IK (llvmlite: cannot load)" in caplog.text
