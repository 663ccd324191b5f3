"""Which sphere pairs get the optimiser's slots: the sphere tables the slots are filled from,
the choice of the closest pairs along a warm start, and the pairs without a slot that a
solution brings too close (the next active-set round's forced pairs).

Arm-arm pairs are chosen per pair of arms (:func:`~streams.motion.sphere_pairs.arm_pairs`),
each pair of arms with its own slot count (from the two arms' coarse sphere models,
:meth:`~streams.motion.optimiser_records.TrajOptOptions.pair_slots`); arm-obstacle and
arm-table pairs per arm.

Each slot constraint is ``|c_i - c_j|^2 - (r_i + r_j + margin)^2 >= lb`` (table:
``z - r - margin >= lb``) with ``lb = 0`` unless an end point itself is closer (the fixed
end points may touch, e.g. a held object on the table at a place), then ``lb`` is that value.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.transforms import FloatArray
from streams.context import WorldContext
from streams.motion.optimiser_records import TrajOptOptions, TransferQuery
from streams.motion.sphere_pairs import (
    HeldSpheres,
    PathSpheres,
    arm_arm_clearance,
    arm_pairs,
    obstacle_clearance,
    table_clearance,
)


@dataclass(frozen=True)
class SphereTable:
    """Spheres of one arm as the optimiser's slots see them: frame index ``(n,)`` (0-based),
    centre in that frame ``(n, 3)`` [m], radius ``(n,)`` [m], of the arm's ``n_frames``
    joint frames (:meth:`~streams.motion.fk_casadi.ArmFK.joint_frames`; a held object's
    spheres hang on the last, moved there from the tool frame by ``T_last_tool``, None: the
    last joint frame is the tool frame)."""

    frame: Any
    centre: FloatArray
    radius: FloatArray
    n_frames: int
    T_last_tool: FloatArray | None = None

    def plus(self, held: HeldSpheres) -> SphereTable:
        """With the held spheres appended (on the last joint frame), as :func:`path_spheres`
        orders them."""
        n = len(held.radius)
        centre = np.asarray(held.centre, dtype=np.float64).reshape(n, 3)
        if self.T_last_tool is not None:
            T = self.T_last_tool
            centre = centre @ T[:3, :3].T + T[:3, 3]
        return SphereTable(
            np.concatenate([self.frame, np.full(n, self.n_frames - 1, dtype=np.int64)]),
            np.concatenate([self.centre, centre]),
            np.concatenate([self.radius, held.radius]),
            self.n_frames,
            self.T_last_tool,
        )

    def slots(self, idx: Any, slots: int) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Slot rows for spheres ``idx``: one-hot frames ``(slots, n_frames)``, centres
        ``(slots, 3)``, radii ``(slots, 1)``; unused slots are zero."""
        idx = np.asarray(idx, dtype=np.int64)
        frame = np.zeros((slots, self.n_frames))
        centre, radius = np.zeros((slots, 3)), np.zeros((slots, 1))
        frame[np.arange(len(idx)), self.frame[idx]] = 1.0
        centre[: len(idx)] = self.centre[idx]
        radius[: len(idx), 0] = self.radius[idx]
        return frame, centre, radius


@dataclass(frozen=True)
class ArmSphereTables:
    """One arm's fine spheres (arm-obstacle and arm-table slots) and coarse spheres
    (arm-arm slots)."""

    fine: SphereTable
    coarse: SphereTable

    def with_held(self, held: HeldSpheres) -> tuple[SphereTable, SphereTable]:
        """Fine and coarse tables with the held object's spheres appended."""
        return self.fine.plus(held), self.coarse.plus(held)


def arm_sphere_tables(ctx: WorldContext, arm: str) -> ArmSphereTables:
    """The sphere tables of ``arm`` from its symbolic FK's sphere models."""
    fk = ctx.fk[arm]

    def table(spheres: Any) -> SphereTable:
        frame = np.asarray(spheres.joint, dtype=np.int64) - 1
        return SphereTable(
            frame, np.asarray(spheres.centre), np.asarray(spheres.radius), fk.dof,
            fk.T_last_tool,
        )  # fmt: skip

    return ArmSphereTables(table(fk.spheres), table(fk.coarse))


def slot_lower_bounds(lb: FloatArray, slots: int) -> FloatArray:
    """``lb`` padded to ``slots`` entries with ``-inf`` (unused slots constrain nothing)."""
    out = np.full(slots, -np.inf)
    out[: len(lb)] = lb
    return out


@dataclass(frozen=True)
class Selection:
    """Chosen pairs: ``aa[p]`` ``(n, 2)`` sphere indices (of the first and second arm of
    pair ``p`` of :func:`~streams.motion.sphere_pairs.arm_pairs`); ``ao[i]`` ``(n, 2)`` (arm
    sphere, obstacle sphere); ``table[i]`` ``(n,)``; and each slot's constraint lower bound."""

    aa: tuple[Any, ...]  # per pair of arms
    ao: tuple[Any, ...]  # per arm
    table: tuple[Any, ...]  # per arm
    aa_lb: tuple[FloatArray, ...]  # per pair of arms
    ao_lb: tuple[FloatArray, ...]  # per arm
    table_lb: tuple[FloatArray, ...]  # per arm


@dataclass(frozen=True)
class Violators:
    """Pairs without a slot that a solution brings too close, per kind (per pair of arms
    arm-arm; per arm arm-obstacle and arm-table)."""

    aa: tuple[set[tuple[int, int]], ...]  # per pair of arms
    ao: tuple[set[tuple[int, int]], ...]  # per arm
    table: tuple[set[int], ...]  # per arm

    def any_left(self) -> bool:
        return bool(any(self.aa) or any(self.ao) or any(self.table))

    def merged(self, other: Selection | None) -> Selection:
        def pairs(base: Any, extra: set[tuple[int, int]]) -> Any:
            have = {tuple(int(v) for v in r) for r in np.asarray(base).reshape(-1, 2)}
            return np.array(sorted(have | extra), dtype=np.int64).reshape(-1, 2)

        def singles(base: Any, extra: set[int]) -> Any:
            return np.array(sorted({int(v) for v in np.asarray(base)} | extra), dtype=np.int64)

        empty2 = np.zeros((0, 2), dtype=np.int64)
        empty1 = np.zeros(0, dtype=np.int64)
        nolb = np.zeros(0)
        aa = tuple(
            pairs(other.aa[p] if other else empty2, extra) for p, extra in enumerate(self.aa)
        )
        arms = range(len(self.ao))
        ao = tuple(pairs(other.ao[i] if other else empty2, self.ao[i]) for i in arms)
        tb = tuple(singles(other.table[i] if other else empty1, self.table[i]) for i in arms)
        nolbs = tuple(nolb for _ in arms)
        return Selection(aa, ao, tb, tuple(nolb for _ in aa), nolbs, nolbs)


def _pick(clear: FloatArray, slots: int, limit: float, forced: Any) -> Any:
    """Indices (rows of ``np.argwhere``) of the ``slots`` smallest entries below ``limit``,
    forced ones first."""
    flat = clear.reshape(-1)
    forced_flat = (
        np.ravel_multi_index(tuple(np.asarray(forced, dtype=np.int64).T), clear.shape)
        if forced is not None and np.asarray(forced).size
        else np.zeros(0, dtype=np.int64)
    )
    first = list(dict.fromkeys(int(i) for i in forced_flat))
    taken = set(first)
    order = [int(i) for i in np.argsort(flat) if flat[i] < limit and int(i) not in taken]
    chosen = (first + order)[:slots]
    return np.stack(np.unravel_index(np.array(chosen, dtype=np.int64), clear.shape), axis=1)


def select_pairs(
    dense: PathSpheres,
    ends: PathSpheres,
    query: TransferQuery,
    o: TrajOptOptions,
    forced: Selection | None,
    pair_slots: tuple[int, ...] | None = None,
) -> Selection:
    """The pairs that get slots: per kind the closest along ``dense`` (the warm start's
    spheres) below ``select_distance``, ``forced`` ones first, each with its lower bound from
    the end points ``ends``. ``pair_slots``: the arm-arm slots of each pair of arms (default
    ``o.arm_arm_slots`` each, see :func:`streams.motion.nlp.pair_slot_counts`).

    Raises:
        ParameterError: neither ``pair_slots`` nor ``o.arm_arm_slots`` is given."""
    pairs = arm_pairs(dense.arms)
    if pair_slots is None:
        if o.arm_arm_slots is None:
            raise ParameterError("select_pairs: give pair_slots or options.arm_arm_slots")
        pair_slots = o.pair_slots((0,) * dense.arms)
    aa, aa_lb = [], []
    for p, (i, j) in enumerate(pairs):
        aa_c = arm_arm_clearance(dense, i, j).min(axis=0)
        sel = _pick(aa_c, pair_slots[p], o.select_distance, forced.aa[p] if forced else None)
        aa_end = arm_arm_clearance(ends, i, j)[:, sel[:, 0], sel[:, 1]]
        rl, rr = ends.coarse_radii[i][sel[:, 0]], ends.coarse_radii[j][sel[:, 1]]
        aa.append(sel)
        aa_lb.append(_lb_sq(aa_end, rl + rr, o.margin))
    ao, ao_lb, tb, tb_lb = [], [], [], []
    oc, orad = query.obstacles
    for i in range(len(query.held)):
        if len(orad):
            c = obstacle_clearance(dense, i, oc, orad).min(axis=0)
            sel = _pick(c, o.obstacle_slots, o.select_distance, forced.ao[i] if forced else None)
            end = obstacle_clearance(ends, i, oc, orad)[:, sel[:, 0], sel[:, 1]]
            ao_lb.append(_lb_sq(end, ends.radii[i][sel[:, 0]] + orad[sel[:, 1]], o.margin))
        else:
            sel, _ = np.zeros((0, 2), dtype=np.int64), None
            ao_lb.append(np.zeros(0))
        ao.append(sel)
        t = table_clearance(dense, i).min(axis=0)
        tsel = _pick(
            t, o.table_slots, o.select_distance, forced.table[i][:, None] if forced else None
        )[:, 0]
        tend = table_clearance(ends, i)[:, tsel].min(axis=0)
        tb.append(tsel)
        tb_lb.append(np.minimum(0.0, tend - o.margin) - 1e-6)
    return Selection(tuple(aa), tuple(ao), tuple(tb), tuple(aa_lb), tuple(ao_lb), tuple(tb_lb))


def _lb_sq(end_clearance: FloatArray, rsum: FloatArray, margin: float) -> FloatArray:
    """Lower bound of ``d^2 - (rsum + margin)^2`` from the end points' clearances ``(2, n)``."""
    d = np.maximum(end_clearance.min(axis=0) + rsum, 0.0)
    out: FloatArray = np.minimum(0.0, d**2 - (rsum + margin) ** 2) - 1e-6
    return out


def violations(
    dense: PathSpheres, ends: PathSpheres, query: TransferQuery, selection: Selection
) -> tuple[float, Violators]:
    """Pairs without a slot that come closer than zero clearance on the dense path (and
    closer than at both end points). Pairs with a slot are the NLP's business."""
    tol = -1e-3
    worst = float("inf")
    bad_aa: list[set[tuple[int, int]]] = []
    for p, (i, j) in enumerate(arm_pairs(dense.arms)):
        aa = arm_arm_clearance(dense, i, j).min(axis=0)
        aa_end = arm_arm_clearance(ends, i, j).min(axis=0)
        bad = {(int(a), int(b)) for a, b in np.argwhere(aa < np.minimum(0.0, aa_end) + tol)}
        bad_aa.append(bad - {(int(a), int(b)) for a, b in selection.aa[p]})
        worst = min(worst, float(aa.min()))
    ao: list[set[tuple[int, int]]] = []
    tb: list[set[int]] = []
    oc, orad = query.obstacles
    for i in range(len(query.held)):
        if len(orad):
            c = obstacle_clearance(dense, i, oc, orad).min(axis=0)
            ce = obstacle_clearance(ends, i, oc, orad).min(axis=0)
            bad = {(int(a), int(b)) for a, b in np.argwhere(c < np.minimum(0.0, ce) + tol)}
            ao.append(bad - {(int(a), int(b)) for a, b in selection.ao[i]})
            worst = min(worst, float(c.min()))
        else:
            ao.append(set())
        t = table_clearance(dense, i).min(axis=0)
        te = table_clearance(ends, i).min(axis=0)
        bad_t = {int(a) for a in np.flatnonzero(t < np.minimum(0.0, te) + tol)}
        tb.append(bad_t - {int(a) for a in selection.table[i]})
        worst = min(worst, float(t.min()))
    return worst, Violators(tuple(bad_aa), tuple(ao), tuple(tb))
