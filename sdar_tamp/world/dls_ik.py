"""Damped-least-squares inverse kinematics over a pinocchio model (any serial arm).

For arms without a closed form; the UR arms use :mod:`sdar_tamp.world.ur_ik`.
Each iteration solves ``dq = -J^T (J J^T + lambda I)^{-1} e`` for the local pose error
``e = log6(T_frame_target)`` and clamps the result into the joint limits.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.world._pin import PinRobot
from sdar_tamp.world.transforms import FloatArray


@dataclass(frozen=True)
class DlsResult:
    """Outcome of one damped-least-squares solve."""

    q: FloatArray
    success: bool
    iterations: int
    error: float  # norm of the final log6 pose error [m, rad]


@dataclass(frozen=True)
class DlsOptions:
    """Solver settings: damping [-], step scale [-], tolerance on the error norm."""

    damping: float = 1e-6
    step: float = 1.0
    tolerance: float = 1e-10
    max_iterations: int = 200

    def __post_init__(self) -> None:
        if self.damping < 0 or self.step <= 0 or self.tolerance <= 0 or self.max_iterations < 1:
            raise ParameterError(
                "DlsOptions: expected damping >= 0, step > 0, tolerance > 0, max_iterations >= 1"
            )


def dls_ik(
    robot: PinRobot,
    frame: int,
    T_base_target: FloatArray,
    q0: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
    options: DlsOptions | None = None,
) -> DlsResult:
    """Solve for ``q`` with ``T_base_frame(q) = T_base_target``, starting from ``q0`` [rad]."""
    opts = options or DlsOptions()
    q = np.clip(np.asarray(q0, dtype=np.float64), lower, upper)
    eye = np.eye(6)
    norm = np.inf
    for it in range(opts.max_iterations):
        err, J = robot.local_error_and_jacobian(q, frame, T_base_target)
        norm = float(np.linalg.norm(err))
        if norm < opts.tolerance:
            return DlsResult(q, True, it, norm)
        dq = -J.T @ np.linalg.solve(J @ J.T + opts.damping * eye, err)
        q = np.clip(robot.integrate(q, opts.step * dq), lower, upper)
    err, _ = robot.local_error_and_jacobian(q, frame, T_base_target)
    norm = float(np.linalg.norm(err))
    return DlsResult(q, norm < opts.tolerance, opts.max_iterations, norm)
