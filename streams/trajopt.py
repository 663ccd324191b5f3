"""Synchronous dual-arm trajectory optimisation (CasADi + IPOPT), built once per shape.

Decision variables: the interior knots of a path ``q_0 .. q_{K-1}`` over every arm (``dof`` joints);
``q_0`` and ``q_{K-1}`` are parameters. Cost: squared second differences (smoothness) plus a
small weight on squared first differences (length). Constraints at every interior knot:

* joint limits (variable bounds);
* per-step joint velocity ``|q_{k+1} - q_k| <= v_max dt`` and acceleration
  ``|q_{k+1} - 2 q_k + q_{k-1}| <= a_max dt^2`` on the nominal time grid ``dt = T / (K - 1)``
  (``T`` per call; the exact timing is :mod:`streams.timing`'s job);
* sphere clearances in *slots*: arm-arm (coarse spheres, held objects included, so the two
  held objects are checked against each other), arm-obstacle per arm, arm-table per arm.
  A slot names one sphere of an arm by parameters (its joint frame, as a one-hot row, and
  its centre and radius in that frame), so the NLP is built once and each call chooses the
  pairs that matter: the ones closest along the warm start,
  refreshed by an active-set round when the solution comes near a pair without a slot.

The evenly spaced straight line is the unconstrained minimiser of the cost; when it satisfies
every constraint (and no pair without a slot comes too close) it is returned without calling
IPOPT (``status == "straight line feasible"``).

Each slot constraint is ``|c_i - c_j|^2 - (r_i + r_j + margin)^2 >= lb`` (table:
``z - r - margin >= lb``) with ``lb = 0`` unless an end point itself is closer (the fixed
end points may touch, e.g. a held object on the table at a place), then ``lb`` is that value.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from sdar_tamp.logs import get_logger
from sdar_tamp.world.transforms import FloatArray
from streams import compiled
from streams._casadi import ca, sx_sym, to_array
from streams.context import WorldContext
from streams.fk_casadi import joint_frames
from streams.sphere_pairs import (
    HeldSpheres,
    PathSpheres,
    arm_arm_clearance,
    obstacle_clearance,
    path_spheres,
    table_clearance,
)

_log = get_logger(__name__)


@dataclass(frozen=True)
class TrajOptOptions:
    """Shape and solver settings; one NLP is built per distinct value."""

    knots: int = 10
    held_slots: int = 4  # spheres per held object
    arm_arm_slots: int = 24
    obstacle_slots: int = 12  # per arm
    table_slots: int = 6  # per arm
    margin: float = 0.015  # [m] clearance asked of the spheres
    select_distance: float = 0.10  # [m] pairs closer than this along the path get a slot
    w_length: float = 0.05
    max_iter: int = 25
    tol: float = 1e-3
    active_set_rounds: int = 2
    compiled: bool = True  # derivatives compiled where a C compiler is (streams.compiled)


@dataclass(frozen=True)
class TransferQuery:
    """One transfer: end configurations ``(dof,)`` [rad], held spheres per arm (scene order),
    obstacle spheres ``(m, 3)``, ``(m,)`` [m] and the nominal duration ``T`` [s]."""

    q_start: FloatArray
    q_goal: FloatArray
    held: tuple[HeldSpheres, ...]
    obstacles: tuple[FloatArray, FloatArray]
    duration: float
    fixed: tuple[bool, ...] = ()  # per arm (scene order): it must wait at its start


@dataclass(frozen=True)
class TrajOptResult:
    """The optimised knots ``(K, dof)``; ``success`` means IPOPT converged (or stopped at a
    feasible point) and every sphere pair keeps its clearance on a dense check of the path."""

    path: FloatArray
    success: bool
    status: str
    iterations: int
    solve_time: float  # [s] wall time of the whole call
    rounds: int = 1
    min_clearance: float = field(default=float("nan"))  # [m] over all sphere pairs


class _Layout:
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


class TrajectoryOptimiser:
    """The NLP for one :class:`TrajOptOptions`, built at construction, solved many times.

    The collision rows of one knot are one small CasADi function of that knot's joints and
    the parameters, mapped over the interior knots (``Function.map``), and so are their
    derivatives (see :meth:`_build`): the build differentiates one knot, not the whole
    horizon, and takes a fraction of a second. A slot names its
    sphere by the joint frame it hangs on (a one-hot row over the six frames of its arm; a
    held sphere hangs on tool0) and its centre [m] and radius [m] in that frame, so the
    graph grows with the frames, not with every sphere of the arm."""

    def __init__(self, ctx: WorldContext, options: TrajOptOptions | None = None) -> None:
        self.ctx = ctx
        self.options = o = options or TrajOptOptions()
        self._arms = self.ctx.layout
        dof = self._arms.dof
        lay = _Layout()
        lay.add("q0", 1, dof)
        lay.add("q1", 1, dof)
        for i in range(len(self._arms)):
            for kind, slots in _slot_kinds(o):
                lay.add(f"{kind}_frame{i}", slots, FRAMES)
                lay.add(f"{kind}_centre{i}", slots, 3)
                lay.add(f"{kind}_radius{i}", slots, 1)
            lay.add(f"ao_obs{i}", o.obstacle_slots, 4)
        lay.add("margin", 1, 1)
        self._lay = lay
        self._spheres = [_arm_sphere_table(ctx, arm) for arm in ctx.arm_names]
        self._build()

    # -- construction ------------------------------------------------------------------
    def _slot_centres(self, frames: list[Any], p: Any, kind: str, i: int) -> tuple[Any, Any]:
        """World centres ``(slots, 3)`` and radii ``(slots, 1)`` of one arm's slots."""
        lay = self._lay
        W, C = lay.sym(p, f"{kind}_frame{i}"), lay.sym(p, f"{kind}_centre{i}")
        n = int(W.shape[0])
        P: Any = 0
        for j, T in enumerate(frames):
            placed = T[:3, :3] @ C.T + ca.repmat(T[:3, 3], 1, n)
            P = P + placed * ca.repmat(W[:, j].T, 3, 1)
        return P.T, lay.sym(p, f"{kind}_radius{i}")

    def _knot_rows(self, q: Any, p: Any) -> Any:
        """The collision rows of one knot ``q`` ``(dof,)``: arm-arm slots, then arm-obstacle
        and arm-table slots per arm."""
        lay, arms = self._lay, self._arms
        m = lay.sym(p, "margin")
        frames = [
            joint_frames(q[sl], self.ctx.fk[arm].T_world_base)
            for arm, sl in zip(self.ctx.arm_names, arms.slices, strict=True)
        ]
        (cl, rl), (cr, rr) = (self._slot_centres(frames[i], p, "aa", i) for i in (0, 1))
        g = [ca.sum2((cl - cr) ** 2) - (rl + rr + m) ** 2]
        for i in range(len(arms)):
            c, r = self._slot_centres(frames[i], p, "ao", i)
            obs = lay.sym(p, f"ao_obs{i}")
            g.append(ca.sum2((c - obs[:, :3]) ** 2) - (r + obs[:, 3] + m) ** 2)
        for i in range(len(arms)):
            c, r = self._slot_centres(frames[i], p, "t", i)
            g.append(c[:, 2] - r - m)
        return ca.vertcat(*g)

    def _build(self) -> None:
        """The NLP over the interior knots, with its derivatives assembled from one knot's:
        the clearance rows, their Jacobian and the Hessian of their weighted sum are small
        SX functions of one knot, mapped over the knots, so CasADi differentiates one knot,
        not the whole horizon (the collision Jacobian and Hessian are block diagonal)."""
        o, lay = self.options, self._lay
        dof, n = self._arms.dof, self.options.knots - 2
        q_k, p_k = sx_sym("q", dof), sx_sym("p", lay.size)
        rows_k = self._knot_rows(q_k, p_k)
        lam_k = sx_sym("lam", int(rows_k.shape[0]))
        rows = ca.Function("knot_rows", [q_k, p_k], [rows_k])
        rows_jac = ca.Function("knot_rows_jac", [q_k, p_k], [rows_k, ca.jacobian(rows_k, q_k)])
        rows_hess = ca.Function(
            "knot_rows_hess",
            [q_k, p_k, lam_k],
            [ca.triu(ca.hessian(ca.dot(lam_k, rows_k), q_k)[0])],
        )
        n_rows = int(rows_k.shape[0])
        self._n_collision = n_rows * n

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
        self._solver = ca.nlpsol("dual_arm_transfer", "ipopt", nlp, opts)
        self._nlp, self._jac_g, self._hess_lag, self._opts = nlp, jac_g, hess_lag, opts
        self._library: Path | None = None  # the compiled derivatives, once they exist
        self.compiled = False
        self._g_fn = ca.Function("g", [x, p], [g])
        scene = self.ctx.scene
        lo, hi = scene.joint_array("lower"), scene.joint_array("upper")
        self._lbx, self._ubx = np.tile(lo, n), np.tile(hi, n)
        self._vmax = scene.joint_array("velocity_limit")
        self._amax = scene.joint_array("acceleration_limit")

    # -- compiled derivatives ------------------------------------------------------------
    def request_compiled(self, flags: Sequence[str] = compiled.FLAGS) -> None:
        """Ask for the Jacobian and Hessian compiled (:mod:`streams.compiled`): from the
        cache, or compiled in the background; :meth:`solve` switches to them once they are
        there. The values are the same; only their evaluation is faster."""
        functions = [self._jac_g, self._hess_lag]
        self._library = compiled.request(functions, "sdar_trajopt", self.recipe(), flags)

    def recipe(self) -> str:
        """What the derivatives' code is made from: the options, the arms' layout and base
        poses, the kinematic parameters and the code that builds the expressions (the key of
        the compiled library; a loaded library is also checked by its values)."""
        from sdar_tamp.world import kinematics, ur_ik
        from streams import _casadi, fk_casadi

        parts = [repr(self.options), repr(self.ctx.layout), repr(ur_ik.UR5E)]
        for arm in self.ctx.arm_names:
            parts.append(np.asarray(self.ctx.fk[arm].T_world_base).tobytes().hex())
        for module in (_casadi, fk_casadi, kinematics, ur_ik):
            parts.append(Path(module.__file__ or "").read_text(encoding="utf-8"))
        parts.append(Path(__file__).read_text(encoding="utf-8"))
        return "\n".join(parts)

    def _use_compiled(self) -> None:
        """Switch the solver to the compiled derivatives when their library has appeared."""
        if self.compiled or self._library is None or not self._library.is_file():
            return
        functions = [self._jac_g, self._hess_lag]
        try:
            jac_g, hess_lag = twins = compiled.load(functions, self._library)
            if not compiled.same_values(functions, twins):
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
        forced: _Selection | None = None
        status, iters, rounds = "not solved", 0, 0
        for rounds in range(1, o.active_set_rounds + 2):
            dense = path_spheres(self.ctx, densify(path, 3), query.held)
            selection = _select(dense, ends, query, o, forced)
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
                worst, violators = _violations(dense, ends, query, selection)
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
            worst, violators = _violations(dense, ends, query, selection)
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
        self, query: TransferQuery, s: _Selection
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        o, lay, K = self.options, self._lay, self.options.knots
        p = np.zeros(lay.size)
        lay.put(p, "q0", query.q_start)
        lay.put(p, "q1", query.q_goal)
        lay.put(p, "margin", np.array([o.margin]))
        for i in range(len(self._arms)):
            fine, coarse = self._spheres[i].with_held(query.held[i])
            chosen = (("aa", coarse, s.aa[:, i]), ("ao", fine, s.ao[i][:, 0]),
                      ("t", fine, s.table[i]))  # fmt: skip
            for (kind, slots), (_, table, idx) in zip(_slot_kinds(o), chosen, strict=True):
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
            [_slot_lb(s.aa_lb, o.arm_arm_slots)]
            + [_slot_lb(lb, o.obstacle_slots) for lb in s.ao_lb]
            + [_slot_lb(lb, o.table_slots) for lb in s.table_lb]
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


#: Joint frames of an arm a sphere may hang on (frame ``j`` carries link ``j + 1``; tool0 is
#: the last).
FRAMES = 6


def _slot_kinds(o: TrajOptOptions) -> tuple[tuple[str, int], ...]:
    """Slot blocks per arm, in the order of the rows: arm-arm, arm-obstacle, arm-table."""
    return (("aa", o.arm_arm_slots), ("ao", o.obstacle_slots), ("t", o.table_slots))


@dataclass(frozen=True)
class _SphereTable:
    """Spheres of one arm as the optimiser's slots see them: frame index ``(n,)`` (0-based),
    centre in that frame ``(n, 3)`` [m], radius ``(n,)`` [m]."""

    frame: Any
    centre: FloatArray
    radius: FloatArray

    def plus(self, held: HeldSpheres) -> _SphereTable:
        """With the held spheres appended (on tool0), as :func:`path_spheres` orders them."""
        n = len(held.radius)
        return _SphereTable(
            np.concatenate([self.frame, np.full(n, FRAMES - 1, dtype=np.int64)]),
            np.concatenate([self.centre, np.asarray(held.centre).reshape(n, 3)]),
            np.concatenate([self.radius, held.radius]),
        )

    def slots(self, idx: Any, slots: int) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Slot rows for spheres ``idx``: one-hot frames ``(slots, FRAMES)``, centres
        ``(slots, 3)``, radii ``(slots, 1)``; unused slots are zero."""
        idx = np.asarray(idx, dtype=np.int64)
        frame = np.zeros((slots, FRAMES))
        centre, radius = np.zeros((slots, 3)), np.zeros((slots, 1))
        frame[np.arange(len(idx)), self.frame[idx]] = 1.0
        centre[: len(idx)] = self.centre[idx]
        radius[: len(idx), 0] = self.radius[idx]
        return frame, centre, radius


@dataclass(frozen=True)
class _ArmSphereTables:
    fine: _SphereTable
    coarse: _SphereTable

    def with_held(self, held: HeldSpheres) -> tuple[_SphereTable, _SphereTable]:
        return self.fine.plus(held), self.coarse.plus(held)


def _arm_sphere_table(ctx: WorldContext, arm: str) -> _ArmSphereTables:
    fk = ctx.fk[arm]

    def table(spheres: Any) -> _SphereTable:
        frame = np.asarray(spheres.joint, dtype=np.int64) - 1
        return _SphereTable(frame, np.asarray(spheres.centre), np.asarray(spheres.radius))

    return _ArmSphereTables(table(fk.spheres), table(fk.coarse))


class OptimiserBuild:
    """A :class:`TrajectoryOptimiser` under construction in a background thread (building the NLP
    takes a few tenths of a second of CPU; planning that needs no optimisation goes on meanwhile).

    :meth:`get` waits for it (``waited`` [s] adds up the waits) and re-raises an error of
    the build. ``build_time`` [s] is the CPU time of the build (NaN until it is done)."""

    def __init__(self, ctx: WorldContext, options: TrajOptOptions, background: bool = True) -> None:
        self.options = options
        self.build_time = float("nan")
        self.waited = 0.0
        self._result: TrajectoryOptimiser | None = None
        self._error: BaseException | None = None
        self._done = threading.Event()
        if background:
            # Not a daemon: the interpreter waits for a build in progress before it shuts down
            # (CasADi code still running during finalisation crashes the process).
            name = "sdar-trajopt-build"
            threading.Thread(target=self._run, args=(ctx,), name=name, daemon=False).start()
        else:
            self._run(ctx)

    def _run(self, ctx: WorldContext) -> None:
        start = time.thread_time()
        try:
            self._result = TrajectoryOptimiser(ctx, self.options)
        except BaseException as error:  # handed to the caller of get()
            self._error = error
        finally:
            self.build_time = time.thread_time() - start
            self._done.set()
        if self._result is not None and self.options.compiled:
            # after the optimiser is handed out: the code generation (about 0.5 s) delays
            # no solve; the solver switches to the compiled derivatives once they exist
            self._request_compiled(self._result)

    @staticmethod
    def _request_compiled(optimiser: TrajectoryOptimiser) -> None:
        """Compiled derivatives are a speed-up only: whatever stops them, the build stands."""
        try:
            optimiser.request_compiled()
        except Exception as error:  # any failure leaves CasADi's own evaluation
            _log.info("compiled derivatives unavailable, kept uncompiled: %s", error)

    @property
    def ready(self) -> bool:
        return self._done.is_set()

    def get(self) -> TrajectoryOptimiser:
        if not self._done.is_set():
            start = time.perf_counter()
            _log.info("waiting for the trajectory optimiser to be built")
            self._done.wait()
            self.waited += time.perf_counter() - start
        if self._error is not None:
            raise self._error
        assert self._result is not None
        return self._result


class OptimiserCache:
    """Optimisers by scene and options, each built once (in the background) and shared by
    every planner that asks for the same pair. A solver is not safe to call from two
    threads at once: share one cache between planners used in one thread."""

    def __init__(self) -> None:
        self._builds: dict[tuple[Any, TrajOptOptions], OptimiserBuild] = {}
        self._lock = threading.Lock()

    def get(
        self, ctx: WorldContext, options: TrajOptOptions | None = None, background: bool = True
    ) -> OptimiserBuild:
        """The build for ``ctx.scene`` and ``options`` (started now if it is the first)."""
        key = (ctx.scene, options or TrajOptOptions())
        with self._lock:
            build = self._builds.get(key)
            if build is None:
                build = self._builds[key] = OptimiserBuild(ctx, key[1], background)
        return build

    def __len__(self) -> int:
        return len(self._builds)


#: The process-wide cache of built optimisers (a warm start for every later solve in the
#: process with the same scene and options).
OPTIMISERS = OptimiserCache()


def _remove(library: Path) -> None:
    """Delete a cached library that must not be used (a read-only cache keeps it: it is
    refused again by its values next time, which costs a few milliseconds)."""
    try:
        library.unlink(missing_ok=True)
    except OSError as error:
        _log.info("could not remove %s: %s", library, error)


def straight_line(q_a: FloatArray, q_b: FloatArray, knots: int) -> FloatArray:
    """``(knots, n)`` evenly spaced configurations from ``q_a`` to ``q_b``."""
    s = np.linspace(0.0, 1.0, knots)[:, None]
    return (1.0 - s) * np.asarray(q_a)[None] + s * np.asarray(q_b)[None]


def densify(path: FloatArray, factor: int) -> FloatArray:
    """The path with ``factor - 1`` evenly spaced points inserted in every segment."""
    s = np.linspace(0.0, 1.0, factor + 1)[:-1]
    seg = path[:-1, None] * (1.0 - s[None, :, None]) + path[1:, None] * s[None, :, None]
    return np.concatenate([seg.reshape(-1, path.shape[1]), path[-1:]])


def _slot_lb(lb: FloatArray, slots: int) -> FloatArray:
    out = np.full(slots, -np.inf)
    out[: len(lb)] = lb
    return out


@dataclass(frozen=True)
class _Selection:
    """Chosen pairs: ``aa`` ``(n, 2)`` sphere indices; ``ao[i]`` ``(n, 2)`` (arm sphere,
    obstacle sphere); ``table[i]`` ``(n,)``; and each slot's constraint lower bound."""

    aa: Any
    ao: tuple[Any, ...]  # per arm
    table: tuple[Any, ...]  # per arm
    aa_lb: FloatArray
    ao_lb: tuple[FloatArray, ...]  # per arm
    table_lb: tuple[FloatArray, ...]  # per arm


@dataclass(frozen=True)
class _Violators:
    aa: set[tuple[int, int]]
    ao: tuple[set[tuple[int, int]], ...]  # per arm
    table: tuple[set[int], ...]  # per arm

    def any_left(self) -> bool:
        return bool(self.aa or any(self.ao) or any(self.table))

    def merged(self, other: _Selection | None) -> _Selection:
        def pairs(base: Any, extra: set[tuple[int, int]]) -> Any:
            have = {tuple(int(v) for v in r) for r in np.asarray(base).reshape(-1, 2)}
            return np.array(sorted(have | extra), dtype=np.int64).reshape(-1, 2)

        def singles(base: Any, extra: set[int]) -> Any:
            return np.array(sorted({int(v) for v in np.asarray(base)} | extra), dtype=np.int64)

        empty2 = np.zeros((0, 2), dtype=np.int64)
        empty1 = np.zeros(0, dtype=np.int64)
        nolb = np.zeros(0)
        aa = pairs(other.aa if other else empty2, self.aa)
        arms = range(len(self.ao))
        ao = tuple(pairs(other.ao[i] if other else empty2, self.ao[i]) for i in arms)
        tb = tuple(singles(other.table[i] if other else empty1, self.table[i]) for i in arms)
        nolbs = tuple(nolb for _ in arms)
        return _Selection(aa, ao, tb, nolb, nolbs, nolbs)


def _pick(clear: FloatArray, slots: int, limit: float, forced: Any) -> Any:
    """Indices (rows of ``np.argwhere``) of the ``slots`` smallest entries below ``limit``,
    forced ones first."""
    flat = clear.reshape(-1)
    forced_flat = (
        np.ravel_multi_index(tuple(np.asarray(forced, dtype=np.int64).T), clear.shape)
        if forced is not None and np.asarray(forced).size
        else np.zeros(0, dtype=np.int64)
    )
    order = [int(i) for i in np.argsort(flat) if flat[i] < limit and i not in set(forced_flat)]
    chosen = (list(dict.fromkeys(int(i) for i in forced_flat)) + order)[:slots]
    return np.stack(np.unravel_index(np.array(chosen, dtype=np.int64), clear.shape), axis=1)


def _select(
    dense: PathSpheres,
    ends: PathSpheres,
    query: TransferQuery,
    o: TrajOptOptions,
    forced: _Selection | None,
) -> _Selection:
    aa_c = arm_arm_clearance(dense).min(axis=0)
    aa = _pick(aa_c, o.arm_arm_slots, o.select_distance, forced.aa if forced else None)
    aa_end = arm_arm_clearance(ends)[:, aa[:, 0], aa[:, 1]]
    rl, rr = ends.coarse_radii[0][aa[:, 0]], ends.coarse_radii[1][aa[:, 1]]
    aa_lb = _lb_sq(aa_end, rl + rr, o.margin)
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
    return _Selection(aa, tuple(ao), tuple(tb), aa_lb, tuple(ao_lb), tuple(tb_lb))


def _lb_sq(end_clearance: FloatArray, rsum: FloatArray, margin: float) -> FloatArray:
    """Lower bound of ``d^2 - (rsum + margin)^2`` from the end points' clearances ``(2, n)``."""
    d = np.maximum(end_clearance.min(axis=0) + rsum, 0.0)
    out: FloatArray = np.minimum(0.0, d**2 - (rsum + margin) ** 2) - 1e-6
    return out


def _violations(
    dense: PathSpheres, ends: PathSpheres, query: TransferQuery, selection: _Selection
) -> tuple[float, _Violators]:
    """Pairs without a slot that come closer than zero clearance on the dense path (and
    closer than at both end points). Pairs with a slot are the NLP's business."""
    tol = -1e-3
    aa = arm_arm_clearance(dense).min(axis=0)
    aa_end = arm_arm_clearance(ends).min(axis=0)
    bad_aa = {(int(a), int(b)) for a, b in np.argwhere(aa < np.minimum(0.0, aa_end) + tol)}
    bad_aa -= {(int(a), int(b)) for a, b in selection.aa}
    worst = float(aa.min())
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
    return worst, _Violators(bad_aa, tuple(ao), tuple(tb))
