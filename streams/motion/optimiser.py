"""Synchronous trajectory optimisation of k arms (CasADi + IPOPT), built once per shape.

The NLP (:mod:`streams.motion.nlp`): the interior knots of a path over every arm, a
smoothness and length cost, joint limits, per-step joint velocity
``|q_{k+1} - q_k| <= v_max dt`` and acceleration ``|q_{k+1} - 2 q_k + q_{k-1}| <= a_max dt^2``
on the nominal time grid ``dt = T / (K - 1)`` (``T`` per call; the exact timing is
:mod:`streams.motion.timing`'s job), and sphere clearances in *slots*: arm-arm (coarse
spheres, held objects included, so two held objects are checked against each other; one
block per pair of arms, none for one arm), arm-obstacle per arm, arm-table per arm. Each
call chooses the pairs that matter (:mod:`streams.motion.slots`): the ones closest along the
warm start, refreshed by an active-set round when the solution comes near a pair without a
slot.

The evenly spaced straight line is the unconstrained minimiser of the cost; when it satisfies
every constraint (and no pair without a slot comes too close) it is returned without calling
IPOPT (``status == "straight line feasible"``).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from sdar_tamp.logs import get_logger
from sdar_tamp.world.transforms import FloatArray
from streams.context import WorldContext
from streams.motion import codegen
from streams.motion._casadi import ca, to_array
from streams.motion.nlp import build_nlp, pair_kind, slot_kinds
from streams.motion.optimiser_records import TrajOptOptions, TrajOptResult, TransferQuery
from streams.motion.slots import (
    Selection,
    arm_sphere_tables,
    select_pairs,
    slot_lower_bounds,
    violations,
)
from streams.motion.sphere_pairs import arm_pairs, path_spheres
from streams.motion.waypoints import densify, straight_line

_log = get_logger(__name__)


class TrajectoryOptimiser:
    """The NLP for one :class:`TrajOptOptions`, built at construction, solved many times.

    The collision rows of one knot are one small CasADi function of that knot's joints and
    the parameters, mapped over the interior knots (``Function.map``), and so are their
    derivatives (see :func:`streams.motion.nlp.build_nlp`): the build differentiates one
    knot, not the whole horizon, and takes a fraction of a second. A slot names its
    sphere by the joint frame it hangs on (a one-hot row over the frames of its arm; a
    held sphere hangs on the tool frame) and its centre [m] and radius [m] in that frame, so the
    graph grows with the frames, not with every sphere of the arm."""

    def __init__(self, ctx: WorldContext, options: TrajOptOptions | None = None) -> None:
        self.ctx = ctx
        self.options = options or TrajOptOptions()
        self._arms = self.ctx.layout
        self._spheres = [arm_sphere_tables(ctx, arm) for arm in ctx.arm_names]
        built = build_nlp(ctx, self.options)
        self._lay = built.layout
        self.pair_slots = built.pair_slots
        self._n_collision = built.n_collision
        self._solver = ca.nlpsol("dual_arm_transfer", "ipopt", built.nlp, built.opts)
        self._nlp, self._jac_g, self._hess_lag = built.nlp, built.jac_g, built.hess_lag
        self._opts = built.opts
        self._library: Path | None = None  # the compiled derivatives, once they exist
        self.compiled = False
        self._g_fn = built.g_fn
        self._lbx, self._ubx = built.lbx, built.ubx
        scene = self.ctx.scene
        self._vmax = scene.joint_array("velocity_limit")
        self._amax = scene.joint_array("acceleration_limit")

    # -- compiled derivatives ------------------------------------------------------------
    def request_compiled(self, flags: Sequence[str] = codegen.FLAGS) -> None:
        """Ask for the Jacobian and Hessian compiled (:mod:`streams.motion.codegen`): from the
        cache, or compiled in the background; :meth:`solve` switches to them once they are
        there. The values are the same; only their evaluation is faster."""
        functions = [self._jac_g, self._hess_lag]
        self._library = codegen.request(functions, "sdar_trajopt", self.recipe(), flags)

    @property
    def library(self) -> Path | None:
        """Where the compiled derivatives are (or will be once compiled) after
        :meth:`request_compiled`; None when they are not asked for or not to be had."""
        return self._library

    def recipe(self) -> str:
        """What the derivatives' code is made from: the options, the arm-arm slots of each pair
        of arms (they follow the sphere models), the arms' layout and base poses, the kinematic
        parameters and the code that builds the expressions (the key of the compiled library;
        a loaded library is also checked by its values)."""
        from sdar_tamp.world import kinematics, ur_ik
        from streams.motion import _casadi, fk_casadi, fk_chain, nlp

        parts = [repr(self.options), repr(self.pair_slots), repr(self.ctx.layout)]
        for arm in self.ctx.arm_names:
            fk = self.ctx.fk[arm]
            parts.append(fk.recipe())
            parts.append(np.asarray(fk.T_world_base).tobytes().hex())
        for module in (_casadi, fk_casadi, fk_chain, kinematics, ur_ik, nlp):
            parts.append(Path(module.__file__ or "").read_text(encoding="utf-8"))
        parts.append(Path(__file__).read_text(encoding="utf-8"))
        return "\n".join(parts)

    def _use_compiled(self) -> None:
        """Switch the solver to the compiled derivatives when their library has appeared."""
        if self.compiled or self._library is None or not self._library.is_file():
            return
        functions = [self._jac_g, self._hess_lag]
        try:
            jac_g, hess_lag = twins = codegen.load(functions, self._library)
            if not codegen.same_values(functions, twins):
                _log.warning("%s gives other values: not used, removed", self._library)
                _remove(self._library)  # compiled again by the next process
            else:
                opts = {**self._opts, "jac_g": jac_g, "hess_lag": hess_lag}
                self._solver = ca.nlpsol("dual_arm_transfer", "ipopt", self._nlp, opts)
                self.compiled = True
                _log.info("trajectory optimiser: compiled derivatives in use (%s)", self._library)
        except RuntimeError as error:
            _log.info("the compiled derivatives could not be loaded, kept uncompiled: %s", error)
            _remove(self._library)  # not what it should be: compiled again
        if not self.compiled:
            self._library = None

    # -- solving -----------------------------------------------------------------------
    def solve(self, query: TransferQuery, warm_start: FloatArray | None = None) -> TrajOptResult:
        """Optimise the transfer; ``warm_start`` ``(K, dof)`` (default: the straight line)."""
        t0 = time.perf_counter()
        self._use_compiled()
        o, K, dof = self.options, self.options.knots, self._arms.dof
        q_a, q_b = np.asarray(query.q_start), np.asarray(query.q_goal)
        straight = warm_start is None
        if warm_start is None:
            warm_start = straight_line(q_a, q_b, K)
        path = np.array(warm_start, dtype=np.float64)
        path[0], path[-1] = q_a, q_b
        ends = path_spheres(self.ctx, np.stack([q_a, q_b]), query.held)
        forced: Selection | None = None
        status, iters, rounds = "not solved", 0, 0
        for rounds in range(1, o.active_set_rounds + 2):
            dense = path_spheres(self.ctx, densify(path, 3), query.held)
            selection = select_pairs(dense, ends, query, o, forced, self.pair_slots)
            p, lbg, ubg = self._parameters(query, selection)
            lbx = np.minimum(self._lbx, path[1:-1].reshape(-1))
            ubx = np.maximum(self._ubx, path[1:-1].reshape(-1))
            for sl, fixed in zip(self._arms.slices, query.fixed, strict=False):
                if fixed:
                    hold = np.tile(q_a[sl], (K - 2, 1))
                    path[1:-1, sl] = hold
                    lbx.reshape(K - 2, dof)[:, sl] = hold
                    ubx.reshape(K - 2, dof)[:, sl] = hold
            if straight and rounds == 1 and self._straight_is_optimal(path, p, lbg, ubg):
                worst, violators = violations(dense, ends, query, selection)
                if not violators.any_left():
                    return TrajOptResult(
                        path, True, "straight line feasible", 0, time.perf_counter() - t0, 0, worst
                    )
            sol = self._solver(x0=path[1:-1].reshape(-1), p=p, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
            stats = self._solver.stats()
            status, iters = str(stats["return_status"]), iters + int(stats["iter_count"])
            path = path.copy()
            path[1:-1] = to_array(sol["x"]).reshape(K - 2, dof)
            g = to_array(self._g_fn(path[1:-1].reshape(-1), p)).reshape(-1)
            feasible = bool(np.all(g >= lbg - 1e-4) and np.all(g <= ubg + 1e-4))
            dense = path_spheres(self.ctx, densify(path, 3), query.held)
            worst, violators = violations(dense, ends, query, selection)
            if feasible and not violators.any_left():
                return TrajOptResult(
                    path, True, status, iters, time.perf_counter() - t0, rounds, worst
                )
            _log.debug(
                "round %d: %s, %d iterations, feasible %s, %s unslotted violators",
                rounds, status, iters, feasible, violators,
            )  # fmt: skip
            forced = violators.merged(forced)
        return TrajOptResult(path, False, status, iters, time.perf_counter() - t0, rounds)

    def _straight_is_optimal(
        self, path: FloatArray, p: FloatArray, lbg: FloatArray, ubg: FloatArray
    ) -> bool:
        """The evenly spaced straight line minimises the (convex quadratic) cost with no
        constraints; when it also satisfies every constraint it is the NLP's optimum."""
        g = to_array(self._g_fn(path[1:-1].reshape(-1), p)).reshape(-1)
        return bool(np.all(g >= lbg) and np.all(g <= ubg))

    def _parameters(
        self, query: TransferQuery, s: Selection
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        o, lay, K = self.options, self._lay, self.options.knots
        p = np.zeros(lay.size)
        lay.put(p, "q0", query.q_start)
        lay.put(p, "q1", query.q_goal)
        lay.put(p, "margin", np.array([o.margin]))
        n = len(self._arms)
        for i in range(n):
            fine, coarse = self._spheres[i].with_held(query.held[i])
            chosen = [(pair_kind(p), coarse, s.aa[p][:, ij.index(i)])
                      for p, ij in enumerate(arm_pairs(n)) if i in ij]  # fmt: skip
            chosen += [("ao", fine, s.ao[i][:, 0]), ("t", fine, s.table[i])]
            kinds = slot_kinds(o, i, n, self.pair_slots)
            for (kind, slots), (_, table, idx) in zip(kinds, chosen, strict=True):
                frame, centre, radius = table.slots(idx, slots)
                lay.put(p, f"{kind}_frame{i}", frame)
                lay.put(p, f"{kind}_centre{i}", centre)
                lay.put(p, f"{kind}_radius{i}", radius)
            obs = np.zeros((o.obstacle_slots, 4))
            idx = s.ao[i][:, 1]
            obs[: len(idx), :3] = query.obstacles[0][idx]
            obs[: len(idx), 3] = query.obstacles[1][idx]
            lay.put(p, f"ao_obs{i}", obs)
        per_knot = np.concatenate(
            [slot_lower_bounds(lb, n) for lb, n in zip(s.aa_lb, self.pair_slots, strict=True)]
            + [slot_lower_bounds(lb, o.obstacle_slots) for lb in s.ao_lb]
            + [slot_lower_bounds(lb, o.table_slots) for lb in s.table_lb]
        )
        dt = query.duration / (K - 1)
        lbg = np.concatenate(
            [np.tile(per_knot, K - 2), np.tile(-self._vmax * dt, K - 1),
             np.tile(-self._amax * dt * dt, K - 2)]
        )  # fmt: skip
        ubg = np.concatenate(
            [np.full(self._n_collision, np.inf), np.tile(self._vmax * dt, K - 1),
             np.tile(self._amax * dt * dt, K - 2)]
        )  # fmt: skip
        return p, lbg, ubg


def _remove(library: Path) -> None:
    """Delete a cached library that must not be used (a read-only cache keeps it: it is
    refused again by its values next time, which costs a few milliseconds)."""
    try:
        library.unlink(missing_ok=True)
    except OSError as error:
        _log.info("could not remove %s: %s", library, error)
