"""Where the replay checks collisions between two samples: linear steps in joint space so that
no tool centre point moves more than a given distance [m] from one check to the next."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.layout import ArmLayout
from sdar_tamp.world.transforms import FloatArray


def tcp_positions(
    q: FloatArray, kins: Mapping[str, ArmKinematics], layout: ArmLayout
) -> FloatArray:
    """Every arm's TCP position ``(m, arms, 3)`` [m] for ``q`` ``(m, dof)`` (closed-form FK)."""
    out = []
    for arm in layout:
        kin = kins[arm]
        out.append((kin.fk_batch(layout.part(q, arm)) @ kin.T_tool0_tcp)[:, :3, 3])
    return np.stack(out, axis=1)


def tcp_subdivisions(
    q: FloatArray, kins: Mapping[str, ArmKinematics], layout: ArmLayout, step: float
) -> NDArray[np.int_]:
    """Per interval of ``q`` ``(K, dof)``: the number of linear steps after which no TCP has
    moved more than ``step`` [m] (refined until it holds). Each interval's count depends on its
    two ends only, so a plan and any stretch of it agree on the points the replay checks."""
    return interval_subdivisions(q[:-1], q[1:], kins, layout, step)


def interval_subdivisions(
    start: FloatArray,
    end: FloatArray,
    kins: Mapping[str, ArmKinematics],
    layout: ArmLayout,
    step: float,
) -> NDArray[np.int_]:
    """:func:`tcp_subdivisions` of the intervals from ``start`` to ``end`` ``(r, dof)``, each
    on its own (the same count as within any sequence it is part of)."""
    chord = np.linalg.norm(
        tcp_positions(end, kins, layout) - tcp_positions(start, kins, layout), axis=2
    ).max(axis=1)
    n: NDArray[np.int_] = np.maximum(1, np.ceil(chord / step)).astype(int)
    for _ in range(30):
        off = np.cumsum(n + 1) - (n + 1)  # first dense point of every interval
        idx = np.repeat(np.arange(len(n)), n + 1)
        frac = (np.arange(len(idx)) - np.repeat(off, n + 1)) / np.repeat(n, n + 1)
        dense = start[idx] + frac[:, None] * (end[idx] - start[idx])
        d = np.linalg.norm(np.diff(tcp_positions(dense, kins, layout), axis=0), axis=2)
        d = d.max(axis=1)
        d[off[1:] - 1] = 0.0  # steps across intervals
        worst = np.maximum.reduceat(np.append(d, 0.0), off)
        bad = worst > step
        if not bad.any():
            break
        n[bad] = np.maximum(n[bad] + 1, np.ceil(1.1 * n[bad] * worst[bad] / step))
    return n
