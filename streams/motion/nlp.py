"""The transfer NLP in CasADi: its parameter vector's layout and its construction.

Decision variables: the interior knots of a path ``q_0 .. q_{K-1}`` over every arm (``dof``
joints); ``q_0`` and ``q_{K-1}`` are parameters. Cost: squared second differences
(smoothness) plus a small weight on squared first differences (length). Constraints at every
interior knot: the sphere clearances of the slots (arm-arm, arm-obstacle and arm-table, see
:mod:`streams.motion.slots`), then the per-step joint velocity and acceleration rows on the
nominal time grid. The arm-arm rows come in one block per pair of arms
(:func:`~streams.motion.sphere_pairs.arm_pairs`: ``k (k - 1) / 2`` blocks for ``k`` arms, none
for one arm), as many rows as that pair's slots (:func:`pair_slot_counts`), then one
arm-obstacle block and one arm-table block per arm. A slot
names one sphere of an arm by parameters (its joint frame, as a one-hot row, and its centre
and radius in that frame), so the NLP is built once per
:class:`~streams.motion.optimiser_records.TrajOptOptions` and each call chooses the pairs.

The collision rows of one knot are one small CasADi function of that knot's joints and the
parameters, mapped over the interior knots (``Function.map``), and so are their derivatives:
the build differentiates one knot, not the whole horizon, and takes a fraction of a second.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.layout import ArmLayout
from sdar_tamp.world.transforms import FloatArray
from streams.context import WorldContext
from streams.motion._casadi import ca, sx_sym
from streams.motion.optimiser_records import TrajOptOptions
from streams.motion.sphere_pairs import arm_pairs

#: Joint frames of a UR arm a sphere may hang on (frame ``j`` carries link ``j + 1``; tool0 is
#: the last); another arm has one per joint (:meth:`streams.motion.fk_casadi.ArmFK.joint_frames`).
FRAMES = 6


def pair_kind(pair: int) -> str:
    """The slot kind of the arm-arm block of pair ``pair`` (its index in
    :func:`~streams.motion.sphere_pairs.arm_pairs`)."""
    return f"aa{pair}"


def pair_slot_counts(ctx: WorldContext, o: TrajOptOptions) -> tuple[int, ...]:
    """The arm-arm slots of every pair of the world's arms, from their coarse sphere models
    (:meth:`~streams.motion.optimiser_records.TrajOptOptions.pair_slots`)."""
    return o.pair_slots(tuple(len(ctx.fk[arm].coarse.radius) for arm in ctx.arm_names))


def slot_kinds(
    o: TrajOptOptions, arm: int, arms: int, pair_slots: tuple[int, ...]
) -> tuple[tuple[str, int], ...]:
    """Slot blocks of arm ``arm`` of ``arms``, in the order of its parameter blocks: the
    arm-arm block of every pair it belongs to (``pair_slots[p]`` slots for pair ``p``),
    then arm-obstacle, then arm-table."""
    pairs = tuple(
        (pair_kind(p), pair_slots[p]) for p, ij in enumerate(arm_pairs(arms)) if arm in ij
    )
    return (*pairs, ("ao", o.obstacle_slots), ("t", o.table_slots))


class ParameterLayout:
    """Offsets of named blocks in a flat parameter vector."""

    def __init__(self) -> None:
        self.blocks: dict[str, tuple[int, tuple[int, int]]] = {}
        self.size = 0

    def add(self, name: str, rows: int, cols: int = 1) -> None:
        self.blocks[name] = (self.size, (rows, cols))
        self.size += rows * cols

    def sym(self, p: Any, name: str) -> Any:
        start, (rows, cols) = self.blocks[name]
        return ca.reshape(p[start : start + rows * cols], cols, rows).T

    def put(self, p: FloatArray, name: str, value: FloatArray) -> None:
        start, (rows, cols) = self.blocks[name]
        p[start : start + rows * cols] = np.asarray(value, dtype=np.float64).reshape(rows * cols)


def parameter_layout(
    arms: ArmLayout,
    o: TrajOptOptions,
    frames: tuple[int, ...] | None = None,
    pair_slots: tuple[int, ...] | None = None,
) -> ParameterLayout:
    """The blocks of the NLP's parameter vector: the end knots, every arm's slots (frame,
    centre, radius per kind, :func:`slot_kinds`; the obstacle spheres of its arm-obstacle
    slots) and the margin. ``frames``: per arm, the frames its spheres may hang on (default
    :data:`FRAMES` each); ``pair_slots``: per pair of arms (default: ``o.arm_arm_slots`` each).

    Raises:
        ParameterError: neither ``pair_slots`` nor ``o.arm_arm_slots`` is given."""
    dof = arms.dof
    per_arm = (FRAMES,) * len(arms) if frames is None else frames
    if pair_slots is None:
        if o.arm_arm_slots is None:
            raise ParameterError("parameter_layout: give pair_slots or options.arm_arm_slots")
        pair_slots = o.pair_slots((0,) * len(arms))
    lay = ParameterLayout()
    lay.add("q0", 1, dof)
    lay.add("q1", 1, dof)
    for i in range(len(arms)):
        for kind, slots in slot_kinds(o, i, len(arms), pair_slots):
            lay.add(f"{kind}_frame{i}", slots, per_arm[i])
            lay.add(f"{kind}_centre{i}", slots, 3)
            lay.add(f"{kind}_radius{i}", slots, 1)
        lay.add(f"ao_obs{i}", o.obstacle_slots, 4)
    lay.add("margin", 1, 1)
    return lay


@dataclass(frozen=True)
class TransferNLP:
    """The built NLP: CasADi's problem (``nlp``), its hand-assembled derivatives (``jac_g``,
    ``hess_lag``) and solver options, ``pair_slots`` (the arm-arm slots of each pair of
    arms), ``g_fn`` (the constraint rows of ``x`` and ``p``),
    ``n_collision`` (the collision rows over all interior knots) and the joint bounds of the
    decision variables ``(n * dof,)``."""

    layout: ParameterLayout
    pair_slots: tuple[int, ...]  # arm-arm slots per pair of arms
    nlp: dict[str, Any]
    jac_g: Any
    hess_lag: Any
    opts: dict[str, Any]
    g_fn: Any
    n_collision: int
    lbx: FloatArray
    ubx: FloatArray


def _slot_centres(lay: ParameterLayout, frames: list[Any], p: Any, kind: str, i: int
                  ) -> tuple[Any, Any]:  # fmt: skip
    """World centres ``(slots, 3)`` and radii ``(slots, 1)`` of one arm's slots."""
    W, C = lay.sym(p, f"{kind}_frame{i}"), lay.sym(p, f"{kind}_centre{i}")
    n = int(W.shape[0])
    P: Any = 0
    for j, T in enumerate(frames):
        placed = T[:3, :3] @ C.T + ca.repmat(T[:3, 3], 1, n)
        P = P + placed * ca.repmat(W[:, j].T, 3, 1)
    return P.T, lay.sym(p, f"{kind}_radius{i}")


def _knot_rows(ctx: WorldContext, lay: ParameterLayout, q: Any, p: Any) -> Any:
    """The collision rows of one knot ``q`` ``(dof,)``: the arm-arm slots of every pair of
    arms, then arm-obstacle slots per arm, then arm-table slots per arm."""
    arms = ctx.layout
    m = lay.sym(p, "margin")
    frames = [ctx.fk[arm].joint_frames(q[sl])
              for arm, sl in zip(ctx.arm_names, arms.slices, strict=True)]  # fmt: skip
    g: list[Any] = []
    for pair, ij in enumerate(arm_pairs(len(arms))):
        kind = pair_kind(pair)
        (cl, rl), (cr, rr) = (_slot_centres(lay, frames[i], p, kind, i) for i in ij)
        g.append(ca.sum2((cl - cr) ** 2) - (rl + rr + m) ** 2)
    for i in range(len(arms)):
        c, r = _slot_centres(lay, frames[i], p, "ao", i)
        obs = lay.sym(p, f"ao_obs{i}")
        g.append(ca.sum2((c - obs[:, :3]) ** 2) - (r + obs[:, 3] + m) ** 2)
    for i in range(len(arms)):
        c, r = _slot_centres(lay, frames[i], p, "t", i)
        g.append(c[:, 2] - r - m)
    return ca.vertcat(*g)


def build_nlp(ctx: WorldContext, o: TrajOptOptions) -> TransferNLP:
    """The NLP over the interior knots, with its derivatives assembled from one knot's:
    the clearance rows, their Jacobian and the Hessian of their weighted sum are small
    SX functions of one knot, mapped over the knots, so CasADi differentiates one knot,
    not the whole horizon (the collision Jacobian and Hessian are block diagonal)."""
    pair_slots = pair_slot_counts(ctx, o)
    frames = tuple(ctx.fk[a].dof for a in ctx.arm_names)  # the joint frames
    lay = parameter_layout(ctx.layout, o, frames, pair_slots)
    dof, n = ctx.layout.dof, o.knots - 2
    q_k, p_k = sx_sym("q", dof), sx_sym("p", lay.size)
    rows_k = _knot_rows(ctx, lay, q_k, p_k)
    lam_k = sx_sym("lam", int(rows_k.shape[0]))
    rows = ca.Function("knot_rows", [q_k, p_k], [rows_k])
    rows_jac = ca.Function("knot_rows_jac", [q_k, p_k], [rows_k, ca.jacobian(rows_k, q_k)])
    rows_hess = ca.Function(
        "knot_rows_hess",
        [q_k, p_k, lam_k],
        [ca.triu(ca.hessian(ca.dot(lam_k, rows_k), q_k)[0])],
    )
    n_rows = int(rows_k.shape[0])

    x, p = ca.MX.sym("x", n * dof), ca.MX.sym("p", lay.size)
    X = ca.reshape(x, dof, n)  # one column per interior knot
    Q = ca.horzcat(lay.sym(p, "q0").T, X, lay.sym(p, "q1").T)
    d1 = Q[:, 1:] - Q[:, :-1]
    d2 = Q[:, 2:] - 2 * Q[:, 1:-1] + Q[:, :-2]
    cost = o.w_length * ca.sumsqr(d1) + ca.sumsqr(d2)
    linear = ca.vertcat(ca.vec(d1), ca.vec(d2))
    g = ca.vertcat(ca.vec(rows.map(n)(X, p)), linear)

    def blocks(M: Any) -> Any:  # (r, dof * n) side by side -> block diagonal
        return ca.diagcat(*[M[:, k * dof : (k + 1) * dof] for k in range(n)])

    g_knots, J_knots = rows_jac.map(n)(X, p)
    jac_g = ca.Function(
        "jac_g", [x, p],
        [ca.vertcat(ca.vec(g_knots), linear),
         ca.vertcat(blocks(J_knots), ca.jacobian(linear, x))],
        ["x", "p"], ["g", "jac_g_x"],
    )  # fmt: skip
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", int(g.shape[0]))
    H_knots = rows_hess.map(n)(X, p, ca.reshape(lam_g[: n_rows * n], n_rows, n))
    hess_lag = ca.Function(
        "hess_lag", [x, p, lam_f, lam_g],
        [lam_f * ca.triu(ca.hessian(cost, x)[0]) + blocks(H_knots)],
        ["x", "p", "lam_f", "lam_g"], ["hess_gamma_x_x"],
    )  # fmt: skip
    nlp = {"x": x, "p": p, "f": cost, "g": g}
    opts = {
        "ipopt.print_level": 0,
        "print_time": False,
        "ipopt.sb": "yes",
        "ipopt.max_iter": o.max_iter,
        "ipopt.tol": o.tol,
        "ipopt.acceptable_tol": 1e-2,
        "ipopt.acceptable_iter": 3,
        "ipopt.constr_viol_tol": 1e-4,
        "ipopt.mu_strategy": "adaptive",
        "jac_g": jac_g,
        "hess_lag": hess_lag,
    }
    scene = ctx.scene
    lo, hi = scene.joint_array("lower"), scene.joint_array("upper")
    return TransferNLP(
        lay, pair_slots, nlp, jac_g, hess_lag, opts, ca.Function("g", [x, p], [g]), n_rows * n,
        np.tile(lo, n), np.tile(hi, n),
    )  # fmt: skip
