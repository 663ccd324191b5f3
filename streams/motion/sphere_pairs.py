"""Numeric sphere clearances along a path of k arms, for choosing the optimiser's pair slots.

Arm-arm clearances are taken for every pair of arms (:func:`arm_pairs`: ``k (k - 1) / 2``
pairs, none for one arm). Arm spheres are those of :class:`streams.motion.spheres.ArmSpheres`
followed by the held-object spheres of that arm (given in the tool0 frame). Clearance of a
sphere pair is ``|c_i - c_j| - r_i - r_j`` [m]; of a sphere and the table, ``z - r``.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from sdar_tamp.world.transforms import FloatArray
from streams.context import WorldContext


@dataclass(frozen=True)
class HeldSpheres:
    """Spheres covering a held object, in the tool0 frame: ``(h, 3)`` [m], ``(h,)`` [m]."""

    centre: FloatArray
    radius: FloatArray

    @staticmethod
    def empty() -> HeldSpheres:
        return HeldSpheres(np.zeros((0, 3)), np.zeros(0))


def arm_pairs(arms: int) -> tuple[tuple[int, int], ...]:
    """The pairs of arm positions ``(i, j)``, ``i < j``, in lexicographic order: ``(0, 1)``
    for two arms, ``(0, 1), (0, 2), (1, 2)`` for three, none for one."""
    return tuple(itertools.combinations(range(arms), 2))


@dataclass(frozen=True)
class PathSpheres:
    """Sphere centres of every arm along a path (layout order): ``(s, n_arm, 3)`` each, and
    radii ``(n_arm,)`` each."""

    centres: tuple[FloatArray, ...]
    radii: tuple[FloatArray, ...]
    moving_link: tuple[FloatArray, ...]  # (n_arm,) bool: sphere may touch the table check
    coarse_centres: tuple[FloatArray, ...]  # the coarse arm spheres + held spheres
    coarse_radii: tuple[FloatArray, ...]

    @property
    def arms(self) -> int:
        return len(self.centres)


def path_spheres(ctx: WorldContext, path: FloatArray, held: tuple[HeldSpheres, ...]) -> PathSpheres:
    """Centres of every arm and held sphere at each configuration of ``path`` ``(s, dof)``;
    ``held``: per arm, in the layout's order."""
    cs: list[FloatArray] = []
    rs: list[FloatArray] = []
    ms: list[FloatArray] = []
    ccs: list[FloatArray] = []
    crs: list[FloatArray] = []
    for i, arm in enumerate(ctx.arm_names):
        fk = ctx.fk[arm]
        q = ctx.layout.part(path, arm)
        c, cc = fk.centres(q), fk.centres(q, coarse=True)
        h = held[i]
        if len(h.radius):
            T = fk.tool0_batch(q)  # (s, 4, 4)
            hc = np.einsum("sij,hj->shi", T[:, :3, :3], h.centre) + T[:, None, :3, 3]
            c = np.concatenate([c, hc], axis=1)
            cc = np.concatenate([cc, hc], axis=1)
        cs.append(c)
        ccs.append(cc)
        rs.append(np.concatenate([fk.spheres.radius, h.radius]))
        crs.append(np.concatenate([fk.coarse.radius, h.radius]))
        ms.append(np.concatenate([fk.spheres.joint >= 2, np.ones(len(h.radius), dtype=bool)]))
    return PathSpheres(tuple(cs), tuple(rs), tuple(ms), tuple(ccs), tuple(crs))


def arm_arm_clearance(ps: PathSpheres, i: int = 0, j: int = 1) -> FloatArray:
    """``(s, n_i, n_j)`` clearances between the coarse spheres of arms ``i`` and ``j``
    (layout positions) [m]."""
    c, r = ps.coarse_centres, ps.coarse_radii
    d = np.linalg.norm(c[i][:, :, None] - c[j][:, None], axis=-1)
    out: FloatArray = d - r[i][:, None] - r[j][None]
    return out


def obstacle_clearance(
    ps: PathSpheres, arm: int, centres: FloatArray, radii: FloatArray
) -> FloatArray:
    """``(s, n_arm, m)`` clearances between one arm's spheres and obstacle spheres [m]."""
    d = np.linalg.norm(ps.centres[arm][:, :, None] - centres[None, None], axis=-1)
    out: FloatArray = d - ps.radii[arm][:, None] - radii[None, None]
    return out


def table_clearance(ps: PathSpheres, arm: int) -> FloatArray:
    """``(s, n_arm)`` heights of the spheres' lowest points above the table [m] (inf for
    spheres on the base and shoulder, which stand on the table)."""
    z = ps.centres[arm][..., 2] - ps.radii[arm][None]
    return np.where(ps.moving_link[arm][None], z, np.inf)
