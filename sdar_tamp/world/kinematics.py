"""World-frame kinematics of one arm: pinocchio FK, batched IK (closed form or numeric).

Frames: ``world`` -> the robot's root link (the arm's base pose) -> ... -> the tool frame
(``tool0``, the flange) -> ``tcp`` (``tcp_offset`` along the tool frame's z, between the finger
pads). A UR-family chain (recognised from the URDF by :func:`.ur_identify.ur_parameters`) gets
the closed form of :mod:`.ur_ik` (eight branches, the DH base turned by pi about z in ROS
descriptions); any other serial chain the batched numeric IK of :mod:`.numeric_ik`, whose
"branches" are distinct solutions found from several seeds, nearest the home first.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from sdar_tamp.world import ik_kernel
from sdar_tamp.world._pin import Chain, PinRobot, chain_to
from sdar_tamp.world.dls_ik import DlsOptions, DlsResult, dls_ik
from sdar_tamp.world.errors import KinematicsError
from sdar_tamp.world.numeric_ik import (
    NumericIKOptions,
    chain_fk,
    numeric_ik_branches,
    numeric_ik_from,
)
from sdar_tamp.world.scene import ArmSpec, Scene
from sdar_tamp.world.transforms import BoolArray, FloatArray, inverse, rot_z, translation
from sdar_tamp.world.ur_identify import ur_parameters
from sdar_tamp.world.ur_ik import URParameters, ur_fk, ur_ik, wrap_into_limits

#: ``T_base_link_dh0``: the DH base frame is the ROS base_link turned by pi about z.
T_BASE_DH = np.eye(4)
T_BASE_DH[:3, :3] = rot_z(np.pi)
#: Branches of the closed form (UR family) and distinct solutions kept by the numeric IK.
CLOSED_FORM_BRANCHES = 8
NUMERIC_BRANCHES = 4
#: The numeric IK's effort in the planner (seeds per pose, rounds of fresh seeds). The
#: null-space pull toward the home fades out below a pose error of 3 mm: near the pose its
#: steps leave the pose by their second-order terms, so with a constant pull the descent only
#: converged once the pull was spent. On the Panda cell's grasp poses
#: (benchmarks/bench_numeric_ik.py --planner) this solves the same grasps as a constant pull
#: with 100 iterations and 4 rounds, as near the home, in fewer iterations.
NUMERIC_OPTIONS = NumericIKOptions(
    seeds=8, iterations=30, rounds=4, null_space_gain=0.1, null_space_fade=0.003
)
#: Continuations (a pre-grasp from its grasp, the steps of a straight tool move from their
#: start: :meth:`ArmKinematics.ik_tcp_from`) keep the pull toward the start, as before: it
#: holds each solution on the start's self-motion, and a start near its target converges in
#: a few iterations anyway.
CONTINUATION_OPTIONS = NumericIKOptions(seeds=8, iterations=100, rounds=4)
#: Largest joint difference [rad] under which two numeric IK solutions of one pose count as one
#: branch. Starts that converge from different seeds land at slightly different points of the
#: same self-motion (a 7-DoF arm's: on the Panda cell's grasps often 0.01 to 0.05 rad apart,
#: since the null-space pull fades out near the pose); kept as separate branches they were
#: checked for collisions one after the other, nearly always with the same outcome, and
#: compared as placements that differ by nothing.
NUMERIC_DISTINCT = 0.2
#: Pose pairs an arm keeps solved by the numeric IK (grasp and pre-grasp; some 500 bytes each).
PAIR_CACHE = 50_000


@dataclass(frozen=True)
class IKSolutions:
    """IK branches for ``n`` targets: ``q`` ``(n, b, dof)`` [rad], ``valid`` ``(n, b)``.

    ``b`` depends on the solver: the closed form's eight branches (a branch is valid when it
    is a real solution and every joint fits the arm's limits after shifting by a multiple of
    2 pi), or the numeric IK's distinct solutions (valid where one converged within limits).
    """

    q: FloatArray
    valid: BoolArray

    def closest(self, q_ref: FloatArray) -> tuple[FloatArray, BoolArray]:
        """Per target, the valid branch nearest to ``q_ref`` ``(dof,)``: ``(n, dof)``, ``(n,)``."""
        dist = np.linalg.norm(self.q - q_ref, axis=-1)
        dist = np.where(self.valid, dist, np.inf)
        best = np.argmin(dist, axis=1)
        q: FloatArray = self.q[np.arange(len(best)), best]
        ok: BoolArray = np.asarray(self.valid.any(axis=1), dtype=np.bool_)
        return q, ok


@dataclass(frozen=True)
class ArmKinematics:
    """Forward and inverse kinematics of one arm, in the world frame."""

    spec: ArmSpec
    robot: PinRobot
    tcp_offset: float  # [m]
    chain: Chain  # the robot's root -> the tool frame
    params: URParameters | None  # read from the URDF (UR family), else None: numeric IK
    T_base_dh: FloatArray = field(default_factory=lambda: T_BASE_DH.copy(), compare=False)
    numeric: NumericIKOptions = NUMERIC_OPTIONS
    #: The arm's base frame (``spec.base_frame``) in the description's root frame: the scene
    #: places the base frame, the chain starts at the root.
    T_root_base: FloatArray = field(default_factory=lambda: np.eye(4), compare=False)
    #: The numeric IK's pose pairs solved so far (see :meth:`ik_tcp_pair`), by the pair's bytes.
    _pairs: dict[bytes, tuple[FloatArray, BoolArray, FloatArray, BoolArray]] = field(
        default_factory=dict, compare=False, repr=False
    )

    @staticmethod
    def from_model(
        spec: ArmSpec,
        urdf: Path,
        *,
        tcp_offset: float,
        package_dirs: tuple[Path, ...] = (),
        tool_frame: str = "tool0",
        joint_names: tuple[str, ...] | None = None,
        numeric: NumericIKOptions = NUMERIC_OPTIONS,
    ) -> ArmKinematics:
        """The kinematics of the arm ``spec`` (base pose, limits, home) described by ``urdf``
        from its root link to ``tool_frame``: the closed form when the chain is a UR-family
        arm, else the numeric IK.

        Raises:
            SceneError: the URDF does not load.
            KinematicsError: ``tool_frame`` is missing, the chain holds a joint that is not a
                one-axis revolute or prismatic joint, its joints are not ``joint_names`` (when
                given), or its joint count is not the arm's.
        """
        robot = PinRobot.load(urdf, package_dirs)
        chain = chain_to(robot, tool_frame)
        names = tuple(j.name for j in chain.joints)
        if joint_names is not None and tuple(joint_names) != names:
            raise KinematicsError(
                f"{urdf.name}: the joints from the root to {tool_frame!r} are {list(names)}, "
                f"not {list(joint_names)}"
            )
        if chain.dof != len(spec.home):
            raise KinematicsError(
                f"{urdf.name}: the chain to {tool_frame!r} has {chain.dof} joints; arm "
                f"{spec.name!r} has {len(spec.home)}"
            )
        T_root_base = _root_to_base(robot, spec.base_frame)
        found = ur_parameters(robot, tool_frame)
        if found is None:
            if numeric.compiled:
                ik_kernel.kernel()  # loaded (or compiled) with the arm, not in its first IK
            return ArmKinematics(
                spec, robot, tcp_offset, chain, None, np.eye(4), numeric, T_root_base
            )
        params, T_base_dh = found
        return ArmKinematics(
            spec, robot, tcp_offset, chain, params, T_base_dh, numeric, T_root_base
        )

    @staticmethod
    def from_scene(scene: Scene, arm: str) -> ArmKinematics:
        """The kinematics of the scene's arm ``arm`` (see :meth:`from_model`): its robot
        description, tool frame, joints and gripper's TCP offset."""
        spec = scene.arm(arm)
        return ArmKinematics.from_model(
            spec,
            spec.urdf,
            tcp_offset=spec.gripper.tcp_offset,
            package_dirs=scene.package_dirs,
            tool_frame=spec.tool_frame,
            joint_names=spec.joint_names,
        )

    @property
    def dof(self) -> int:
        return self.chain.dof

    @property
    def tool_frame(self) -> str:
        return self.chain.frame

    @property
    def closed_form(self) -> bool:
        """True for a UR-family arm (closed-form IK, eight branches)."""
        return self.params is not None

    @property
    def branches(self) -> int:
        """Branches of :class:`IKSolutions` this arm's IK returns."""
        return CLOSED_FORM_BRANCHES if self.closed_form else NUMERIC_BRANCHES

    @property
    def T_world_base(self) -> FloatArray:
        """The description's root frame in the world (the chain's start): the scene's base
        pose of the arm's base frame, less the base frame's place on the root."""
        return self.spec.T_world_base @ inverse(self.T_root_base)

    @property
    def T_tool0_tcp(self) -> FloatArray:
        return translation(0.0, 0.0, self.tcp_offset)

    # -- forward kinematics (pinocchio) --------------------------------------------------
    def fk(self, q: FloatArray, frame: str | None = None) -> FloatArray:
        """``T_world_frame`` ``(4, 4)`` for ``q`` ``(dof,)`` [rad], any frame of the URDF
        (default: the tool frame)."""
        full = self._full(self._check_q(q))
        fid = self.robot.frame_id(self.tool_frame if frame is None else frame)
        return self.T_world_base @ self.robot.frame_pose(full, fid)

    def fk_tool0(self, q: FloatArray) -> FloatArray:
        return self.fk(q)

    def fk_tcp(self, q: FloatArray) -> FloatArray:
        """The TCP pose: the URDF's ``tcp`` frame if it has one, else ``tcp_offset`` (the arm's
        gripper's) along the tool frame's z."""
        if self.robot.model.existFrame("tcp"):
            return self.fk(q, "tcp")
        return self.fk(q) @ self.T_tool0_tcp

    # -- batched -------------------------------------------------------------------------
    def fk_batch(self, q: FloatArray) -> FloatArray:
        """``T_world_tool0`` ``(n, 4, 4)`` for ``q`` ``(n, dof)`` (numpy: the closed form of a
        UR arm, else the chain's)."""
        if self.params is not None:
            return self.T_world_base @ self.T_base_dh @ ur_fk(self.params, q)
        _, end = chain_fk(self.chain, q)
        out: FloatArray = self.T_world_base @ end
        return out

    def ik_tool0(self, T_world_tool0: FloatArray) -> IKSolutions:
        """IK branches for tool-frame poses ``(n, 4, 4)`` (or one ``(4, 4)``)."""
        T = self._poses(T_world_tool0)
        if self.params is None:
            T_root = inverse(self.T_world_base) @ T
            lo, hi = self.spec.lower_array, self.spec.upper_array
            home = np.asarray(self.spec.home, dtype=np.float64)
            q_n, ok = numeric_ik_branches(
                self.chain, T_root, lo, hi, home, NUMERIC_BRANCHES, self.numeric,
                distinct=NUMERIC_DISTINCT,
            )  # fmt: skip
            return IKSolutions(q_n, ok)
        T_dh = inverse(self.T_world_base @ self.T_base_dh) @ T
        q, real = ur_ik(self.params, T_dh)
        q, fits = wrap_into_limits(q, self.spec.lower_array, self.spec.upper_array)
        return IKSolutions(q, real & fits)

    def ik_tcp(self, T_world_tcp: FloatArray) -> IKSolutions:
        """IK branches for tool-centre-point poses ``(n, 4, 4)``."""
        T = np.asarray(T_world_tcp, dtype=np.float64)
        return self.ik_tool0(T @ inverse(self.T_tool0_tcp))

    def ik_tcp_from(self, T_world_tcp: FloatArray, starts: FloatArray) -> IKSolutions:
        """Solutions continuing given configurations: for TCP poses ``(n, 4, 4)`` and starts
        ``(n, b, dof)``, the solution of each start's branch ``(n, b, dof)``: the valid closed-
        form branch nearest to the start (largest joint difference), or the numeric IK from
        the start itself."""
        T = self._poses(T_world_tcp) @ inverse(self.T_tool0_tcp)
        q0 = np.asarray(starts, dtype=np.float64)
        if q0.ndim != 3 or q0.shape[0] != len(T) or q0.shape[2] != self.dof:
            raise KinematicsError(
                f"expected starts of shape ({len(T)}, b, {self.dof}), got {q0.shape}"
            )
        if self.params is None:
            T_root = inverse(self.T_world_base) @ T
            lo, hi = self.spec.lower_array, self.spec.upper_array
            q_n, ok = numeric_ik_from(self.chain, T_root, lo, hi, q0, CONTINUATION_OPTIONS)
            return IKSolutions(q_n, ok)
        sol = self.ik_tool0(T)
        d = np.abs(sol.q[:, None, :, :] - q0[:, :, None, :]).max(axis=-1)  # (n, b, 8)
        d = np.where(sol.valid[:, None, :], d, np.inf)
        best = np.argmin(d, axis=2)
        rows = np.arange(len(T))[:, None]
        valid = np.asarray(np.isfinite(np.take_along_axis(d, best[..., None], 2)[..., 0]))
        return IKSolutions(sol.q[rows, best], valid)

    def ik_tcp_pair(
        self, T_first: FloatArray, T_second: FloatArray
    ) -> tuple[IKSolutions, IKSolutions]:
        """IK of pose pairs ``(n, 4, 4)`` each (a grasp and its pre-grasp) where branch ``b``
        of the second continues branch ``b`` of the first (for the closed form its own branch
        index; for the numeric IK the solution from the first's configuration)."""
        T1, T2 = self._poses(T_first), self._poses(T_second)
        if len(T1) != len(T2):
            raise KinematicsError(f"expected as many first as second poses, {len(T1)} != {len(T2)}")
        if self.params is not None:
            both = self.ik_tcp(np.concatenate([T1, T2]))
            n = len(T1)
            return IKSolutions(both.q[:n], both.valid[:n]), IKSolutions(both.q[n:], both.valid[n:])
        return self._numeric_pair(T1, T2)

    def _numeric_pair(self, T1: FloatArray, T2: FloatArray) -> tuple[IKSolutions, IKSolutions]:
        """:meth:`ik_tcp_pair` by the numeric IK, each pair solved once: the pairs met before
        are read from the arm's table (up to :data:`PAIR_CACHE` pairs, then it starts over),
        the others solved in one batch."""
        keys = [T1[i].tobytes() + T2[i].tobytes() for i in range(len(T1))]
        if not keys:
            empty = IKSolutions(
                np.zeros((0, self.branches, self.dof)), np.zeros((0, self.branches), np.bool_)
            )
            return empty, empty
        todo: dict[bytes, int] = {}
        for i, k in enumerate(keys):
            if k not in self._pairs and k not in todo:
                todo[k] = i
        if todo:
            rows = list(todo.values())
            first = self.ik_tcp(T1[rows])
            second = self.ik_tcp_from(T2[rows], first.q)
            if len(self._pairs) + len(rows) > PAIR_CACHE:
                self._pairs.clear()
            for j, k in enumerate(todo):
                valid = second.valid[j] & first.valid[j]
                self._pairs[k] = (first.q[j], first.valid[j], second.q[j], valid)
        got = [self._pairs[k] for k in keys]
        return (
            IKSolutions(np.stack([g[0] for g in got]), np.stack([g[1] for g in got])),
            IKSolutions(np.stack([g[2] for g in got]), np.stack([g[3] for g in got])),
        )

    # -- numerical IK (pinocchio) ----------------------------------------------------------
    def ik_dls(
        self,
        T_world_frame: FloatArray,
        q0: FloatArray,
        frame: str = "tool0",
        options: DlsOptions | None = None,
    ) -> DlsResult:
        """Damped-least-squares IK for any frame, from the start guess ``q0`` [rad] (a robot
        description whose only joints are the arm's)."""
        if self.robot.nq != self.dof:
            raise KinematicsError(
                f"ik_dls: {self.robot.urdf_path.name} has {self.robot.nq} joints, the arm "
                f"{self.dof}"
            )
        T_base = inverse(self.T_world_base) @ np.asarray(T_world_frame, dtype=np.float64)
        return dls_ik(
            self.robot,
            self.robot.frame_id(frame),
            T_base,
            self._check_q(q0),
            self.spec.lower_array,
            self.spec.upper_array,
            options,
        )

    def _poses(self, T: FloatArray) -> FloatArray:
        Ta = np.asarray(T, dtype=np.float64)
        if Ta.shape[-2:] != (4, 4):
            raise KinematicsError(f"expected poses of shape (n, 4, 4), got {Ta.shape}")
        return Ta.reshape(-1, 4, 4)

    def _full(self, q: FloatArray) -> FloatArray:
        """The robot's configuration vector ``(nq,)`` with the arm's joints at ``q``, any other
        joint (fingers) where the arm's ``locked_joints`` hold it (default 0)."""
        if self.robot.nq == self.dof:
            return q
        full = self._locked.copy()
        full[[j.q_index for j in self.chain.joints]] = q
        return full

    @cached_property
    def _locked(self) -> FloatArray:
        full = np.zeros(self.robot.nq)
        model = self.robot.model
        for name, value in self.spec.locked_joints:
            if model.existJointName(name):
                joint = model.joints[int(model.getJointId(name))]
                if int(joint.nq) == 1:
                    full[int(joint.idx_q)] = value
        return full

    def _check_q(self, q: FloatArray) -> FloatArray:
        qa = np.asarray(q, dtype=np.float64)
        if qa.shape != (self.dof,):
            raise KinematicsError(
                f"expected a configuration of shape ({self.dof},), got {qa.shape}"
            )
        return qa


def _root_to_base(robot: PinRobot, base_frame: str) -> FloatArray:
    """``T_root_base`` ``(4, 4)`` of the frame ``base_frame``, which no joint may move.

    Raises:
        KinematicsError: the frame is missing or a joint moves it.
    """
    fid = robot.frame_id(base_frame)
    if int(robot.model.frames[fid].parentJoint) != 0:
        raise KinematicsError(
            f"{robot.urdf_path.name}: the base frame {base_frame!r} is moved by a joint; the "
            "base frame is fixed to the description's root"
        )
    return robot.frame_pose(robot.neutral(), fid)
