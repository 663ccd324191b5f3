"""Buffer sampling: free, reachable temporary poses for an object on the workspace.

A buffer is a planar pose ``(x, y, yaw)`` of the object such that its footprint (grown by
``margin``) lies inside the workspace, overlaps no footprint in ``occupied`` (current object
footprints and goal footprints still to be filled) nor another returned buffer, and the arm
reaches it with a top-down grasp (its IK, closed form or numeric: any branch within the joint
limits, for the grasp and its pre-grasp). Randomness comes from
``numpy.random.default_rng(seed)`` only.
"""

from __future__ import annotations

from collections.abc import Hashable, Mapping, Sequence

import numpy as np
import numpy.typing as npt

from sdar_tamp.world.footprint import clearance, corners, inside_rectangle, overlap_matrix
from sdar_tamp.world.instance import Pose2D
from sdar_tamp.world.scene import Workspace
from sdar_tamp.world.transforms import BoolArray, FloatArray, pose_xyz_yaw
from streams.context import WorldContext
from streams.grasps import Grasp, pregrasp_offset, sample_grasps

IntArray = npt.NDArray[np.intp]


def reachable_top_down(
    ctx: WorldContext,
    arm: str,
    poses: FloatArray,
    size: tuple[float, float, float],
    lift: float = 0.08,
    grasps: Sequence[Grasp] | None = None,
) -> BoolArray:
    """``(n,)``: the arm reaches object poses ``(n, 3)`` (x, y, yaw) with a top-down grasp."""
    p = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    if len(p) == 0:
        return np.zeros(0, dtype=np.bool_)
    top = [g for g in (grasps or sample_grasps(size, ctx.scene.grasp_limits, ())) if g.is_top_down]
    if not top:
        return np.zeros(len(p), dtype=np.bool_)
    T_obj = pose_xyz_yaw(p[:, 0], p[:, 1], size[2] / 2.0, p[:, 2])  # (n, 4, 4)
    T_tcp = (T_obj[:, None] @ np.stack([g.T_object_tcp for g in top])[None]).reshape(-1, 4, 4)
    grasp, pre = ctx.kinematics[arm].ik_tcp_pair(T_tcp, pregrasp_offset(T_tcp, lift))
    ok = grasp.valid & pre.valid
    return np.asarray(ok.reshape(len(p), -1).any(axis=1), dtype=np.bool_)


def sample_buffers(
    ctx: WorldContext,
    arm: str,
    size: tuple[float, float, float],
    occupied: FloatArray,
    k: int,
    seed: int,
    workspace: Workspace | None = None,
    margin: float = 0.01,
    batch: int = 256,
    max_batches: int = 20,
) -> list[Pose2D]:
    """Up to ``k`` buffer poses for an object of ``size`` [m] (fewer if space runs out).

    ``occupied``: footprints ``(m, 4, 2)`` [m] to keep clear (see
    :func:`sdar_tamp.world.footprint.corners`).
    """
    if k < 0:
        raise ValueError(f"k must be >= 0, got {k}")
    ws = workspace or ctx.scene.workspace
    rng = np.random.default_rng(seed)
    taken: FloatArray = np.asarray(occupied, dtype=np.float64).reshape(-1, 4, 2)
    grown = np.array([size[0] + 2 * margin, size[1] + 2 * margin])
    out: list[Pose2D] = []
    for _ in range(max_batches):
        if len(out) >= k:
            break
        cand = np.stack(
            [rng.uniform(*ws.x, batch), rng.uniform(*ws.y, batch),
             rng.choice([0.0, np.pi / 2], batch) + rng.uniform(-0.3, 0.3, batch)], axis=1,
        )  # fmt: skip
        rect = corners(cand, np.broadcast_to(grown, (batch, 2)))
        keep = inside_rectangle(corners(cand, np.broadcast_to(size[:2], (batch, 2))), ws.x, ws.y)
        if len(taken):
            keep &= ~overlap_matrix(rect, taken).any(axis=1)
        idx = np.flatnonzero(keep)
        if len(idx) == 0:
            continue
        idx = idx[reachable_top_down(ctx, arm, cand[idx], size)]
        for i in idx:
            if len(out) >= k:
                break
            if len(taken) and overlap_matrix(rect[i : i + 1], taken).any():
                continue
            out.append(Pose2D(float(cand[i, 0]), float(cand[i, 1]), float(cand[i, 2])))
            taken = np.concatenate([taken, rect[i : i + 1]])
    return out


#: Clearance [m] a buffer keeps, when the table allows, from every other footprint: a finger
#: needs about 2.2 cm beside the object it grasps on the closing axis (1 cm from the open pad,
#: then the 1.2 cm finger), plus the IK's 3 mm; so both the buffered object and its
#: neighbours keep a grasp on every side.
GRASP_CORRIDOR = 0.025


#: Poses whose reach a numeric-IK arm checks in one batch when :meth:`BufferPool.take` meets
#: one it does not know yet.
REACH_CHUNK = 32


class BufferPool:
    """Candidate buffer poses of one object size, inside the workspace, with the arms that
    reach each top-down (:func:`reachable_top_down`): that depends on neither the other
    objects nor the call, so ``count`` poses are sampled once and each call only measures
    their clearance from its footprints (:meth:`clearance`) and takes some of the clear ones
    (:meth:`take`). Randomness: ``numpy.random.default_rng(seed)`` for the pool, the call's
    seed for the order in which poses are taken.

    A closed-form arm's reach is computed for the whole pool at once and ``take`` draws from
    the clear poses it reaches. A numeric-IK arm's costs milliseconds a pose (thousands of
    poses: tens of seconds), so ``take`` draws from the clear poses and checks the reach of
    those it meets, :data:`REACH_CHUNK` at a time, keeping what it learnt."""

    def __init__(
        self,
        ctx: WorldContext,
        size: tuple[float, float, float],
        seed: int,
        workspace: Workspace | None = None,
        count: int = 4096,
    ) -> None:
        if count < 1:
            raise ValueError(f"count must be >= 1, got {count}")
        self.size = size
        ws = workspace or ctx.scene.workspace
        rng = np.random.default_rng(seed)
        cand = np.stack(
            [rng.uniform(*ws.x, count), rng.uniform(*ws.y, count),
             rng.choice([0.0, np.pi / 2], count) + rng.uniform(-0.3, 0.3, count)], axis=1,
        )  # fmt: skip
        rect = corners(cand, np.broadcast_to(size[:2], (count, 2)))
        inside = inside_rectangle(rect, ws.x, ws.y)
        self.poses: FloatArray = cand[inside]  # (n, 3)
        self.rect: FloatArray = rect[inside]  # (n, 4, 2)
        self._near: dict[Hashable, tuple[IntArray, FloatArray]] = {}
        self._ctx = ctx
        #: Per arm, which poses it reaches: computed for every pose at once for a closed-form
        #: arm (microseconds a pose), else filled in by :meth:`take` as it meets them.
        self.reach: dict[str, BoolArray] = {}
        self._known: dict[str, BoolArray] = {}
        for arm in ctx.arm_names:
            eager = ctx.kinematics[arm].closed_form
            self.reach[arm] = (
                reachable_top_down(ctx, arm, self.poses, size)
                if eager
                else np.zeros(len(self.poses), dtype=np.bool_)
            )
            self._known[arm] = np.full(len(self.poses), eager, dtype=np.bool_)

    def known(self, arm: str) -> BoolArray:
        """``(n,)``: the poses whose reach by ``arm`` is known (in :attr:`reach`)."""
        return self._known[arm]

    def _reaches(self, arm: str, i: int, order: IntArray, at: int) -> bool:
        """Whether ``arm`` reaches pose ``i`` (``order[at]``); an unknown pose is checked with
        the next :data:`REACH_CHUNK` unknown poses of ``order`` in one batch."""
        known, reach = self._known[arm], self.reach[arm]
        if not known[i]:
            ahead = order[at:]
            batch = ahead[~known[ahead]][:REACH_CHUNK]
            reach[batch] = reachable_top_down(self._ctx, arm, self.poses[batch], self.size)
            known[batch] = True
        return bool(reach[i])

    def clearance(self, occupied: Mapping[Hashable, FloatArray]) -> FloatArray:
        """``(n,)`` [m]: how far each pose's footprint may grow and stay clear of the
        footprints ``occupied`` (key -> corners ``(4, 2)`` [m]; ``inf`` beyond
        :data:`GRASP_CORRIDOR`, see :func:`~sdar_tamp.world.footprint.clearance`). The
        clearance from one footprint is kept under its key (an object and its pose), so a
        call only computes it for footprints it has not seen."""
        out = np.full(len(self.poses), np.inf)
        for key, rect in occupied.items():
            near = self._near.get(key)
            if near is None:
                c = clearance(self.rect, rect, GRASP_CORRIDOR)
                idx = np.flatnonzero(np.isfinite(c))
                near = self._near[key] = (idx, c[idx])
            idx, value = near
            out[idx] = np.minimum(out[idx], value)
        return out

    def take(self, arm: str, clear: FloatArray, k: int, seed: int, margin: float) -> list[Pose2D]:
        """Up to ``k`` poses ``arm`` reaches whose footprints, grown by ``margin`` [m], overlap
        nothing (``clear > margin``, ``clear`` from :meth:`clearance`) nor one another."""
        if k < 0:
            raise ValueError(f"k must be >= 0, got {k}")
        if not 0.0 <= margin <= GRASP_CORRIDOR:
            raise ValueError(f"margin must be in [0, {GRASP_CORRIDOR}] [m], got {margin}")
        lazy = not self._ctx.kinematics[arm].closed_form
        free = np.flatnonzero((clear > margin) & (self.reach[arm] | lazy))
        grown = np.array([self.size[0] + 2 * margin, self.size[1] + 2 * margin])
        out: list[Pose2D] = []
        chosen: list[FloatArray] = []
        order = np.random.default_rng(seed).permutation(free)
        for at, i in enumerate(order):
            if len(out) >= k:
                break
            if lazy and not self._reaches(arm, int(i), order, at):
                continue
            rect = corners(self.poses[i : i + 1], grown[None])
            if chosen and overlap_matrix(rect, np.concatenate(chosen)).any():
                continue
            out.append(Pose2D(*(float(v) for v in self.poses[i])))
            chosen.append(rect)
        return out
