"""Closed-form forward and inverse kinematics of UR arms, batched with numpy.

Everything here is in the DH base frame and ends at the flange (DH frame 6 = ``tool0``).
Standard DH convention, ``T_{i-1,i} = Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)`` with
``alpha = (pi/2, 0, 0, pi/2, -pi/2, 0)`` and ``a1 = d2 = d3 = a4 = a5 = a6 = 0``.

Derivation of the inverse (joint axes 2, 3, 4 are parallel, along ``z1``):

1. The wrist point ``p5 = p6 - d6 z6`` satisfies ``p5 . z1 = d4`` with
   ``z1 = (sin q1, -cos q1, 0)``; so ``q1 = psi + asin(d4 / r)`` or ``psi + pi - asin(d4 / r)``.
2. ``z6 . z1 = cos q5``, two signs of ``q5``.
3. ``z1`` in flange coordinates is ``(sin q5 cos q6, -sin q5 sin q6, cos q5)``, giving ``q6``
   (arbitrary, 0, when ``sin q5 = 0``).
4. ``T_1_4`` is then known; its planar part is a two-link arm (``a2``, ``a3``): two elbow
   solutions for ``q3``, then ``q2``, and ``q4 = angle(T_1_4) - q2 - q3``.

Branch ``b`` in ``0..7`` is ``4 * shoulder + 2 * wrist + elbow``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sdar_tamp.world.transforms import BoolArray, FloatArray, inverse

_EPS = 1e-9


@dataclass(frozen=True)
class URParameters:
    """The non-zero DH lengths of a UR arm [m]."""

    d1: float
    a2: float
    a3: float
    d4: float
    d5: float
    d6: float


UR5E = URParameters(d1=0.1625, a2=-0.425, a3=-0.3922, d4=0.1333, d5=0.0997, d6=0.0996)


def _dh(theta: FloatArray, d: float, a: float, alpha: float) -> FloatArray:
    """``Rz(theta) Tz(d) Tx(a) Rx(alpha)`` for ``theta`` of shape ``(...)``."""
    ct, st = np.cos(theta), np.sin(theta)
    ca, sa = np.cos(alpha), np.sin(alpha)
    out = np.zeros((*theta.shape, 4, 4))
    out[..., 0, 0] = ct
    out[..., 0, 1] = -st * ca
    out[..., 0, 2] = st * sa
    out[..., 0, 3] = a * ct
    out[..., 1, 0] = st
    out[..., 1, 1] = ct * ca
    out[..., 1, 2] = -ct * sa
    out[..., 1, 3] = a * st
    out[..., 2, 1] = sa
    out[..., 2, 2] = ca
    out[..., 2, 3] = d
    out[..., 3, 3] = 1.0
    return out


def _rows(p: URParameters) -> tuple[tuple[float, float, float], ...]:
    h = np.pi / 2
    return ((p.d1, 0.0, h), (0.0, p.a2, 0.0), (0.0, p.a3, 0.0), (p.d4, 0.0, h), (p.d5, 0.0, -h),
            (p.d6, 0.0, 0.0))  # fmt: skip


def ur_fk(params: URParameters, q: FloatArray) -> FloatArray:
    """Flange poses ``T_dh0_flange`` of shape ``(..., 4, 4)`` for joints ``q`` ``(..., 6)``."""
    q = np.asarray(q, dtype=np.float64)
    T = np.broadcast_to(np.eye(4), (*q.shape[:-1], 4, 4)).copy()
    for i, (d, a, alpha) in enumerate(_rows(params)):
        T = T @ _dh(q[..., i], d, a, alpha)
    return T


def ur_ik(params: URParameters, T_dh0_flange: FloatArray) -> tuple[FloatArray, BoolArray]:
    """All closed-form solutions for flange poses ``(n, 4, 4)``.

    Returns ``q`` of shape ``(n, 8, 6)`` with angles in ``(-pi, pi]`` and ``valid`` ``(n, 8)``,
    False where the branch has no real solution (target out of reach). Invalid rows of ``q``
    hold finite garbage.
    """
    T = np.asarray(T_dh0_flange, dtype=np.float64)
    n = T.shape[0]
    p = params
    x6, y6, z6, p6 = T[:, :3, 0], T[:, :3, 1], T[:, :3, 2], T[:, :3, 3]
    p5 = p6 - p.d6 * z6
    r = np.hypot(p5[:, 0], p5[:, 1])
    ok1 = r >= abs(p.d4) - _EPS
    alpha = np.arcsin(np.clip(p.d4 / np.maximum(r, _EPS), -1.0, 1.0))
    psi = np.arctan2(p5[:, 1], p5[:, 0])
    q1 = np.stack([psi + alpha, psi + np.pi - alpha], axis=1)  # (n, 2)
    s1, c1 = np.sin(q1), np.cos(q1)
    # z1 . v for v in the target frame axes, shape (n, 2)
    c5 = np.clip(z6[:, None, 0] * s1 - z6[:, None, 1] * c1, -1.0, 1.0)
    q5 = np.arccos(c5)[:, :, None] * np.array([1.0, -1.0])  # (n, 2, 2)
    s5 = np.sin(q5)
    zx = (x6[:, None, 0] * s1 - x6[:, None, 1] * c1)[:, :, None]
    zy = (y6[:, None, 0] * s1 - y6[:, None, 1] * c1)[:, :, None]
    safe = np.abs(s5) > _EPS
    s5s = np.where(safe, s5, 1.0)
    q6 = np.where(safe, np.arctan2(-zy / s5s, zx / s5s), 0.0)  # (n, 2, 2)
    # T_1_4 = inv(T_0_1) T_0_6 inv(T_4_6)
    rows = _rows(p)
    T01 = _dh(q1, *rows[0])  # (n, 2, 4, 4)
    T46 = _dh(q5, *rows[4]) @ _dh(q6, *rows[5])  # (n, 2, 2, 4, 4)
    T10 = inverse(T01)
    T14 = T10[:, :, None] @ T[:, None, None] @ inverse(T46)  # (n, 2, 2, 4, 4)
    x, y = T14[..., 0, 3], T14[..., 1, 3]
    c3 = (x * x + y * y - p.a2**2 - p.a3**2) / (2.0 * p.a2 * p.a3)
    ok3 = np.abs(c3) <= 1.0 + _EPS
    q3 = np.arccos(np.clip(c3, -1.0, 1.0))[..., None] * np.array([1.0, -1.0])  # (n,2,2,2)
    q2 = np.arctan2(y, x)[..., None] - np.arctan2(p.a3 * np.sin(q3), p.a2 + p.a3 * np.cos(q3))
    q234 = np.arctan2(T14[..., 1, 0], T14[..., 0, 0])[..., None]
    q4 = q234 - q2 - q3
    shape = (n, 2, 2, 2)
    q = np.stack(
        [
            np.broadcast_to(q1[:, :, None, None], shape),
            q2,
            q3,
            q4,
            np.broadcast_to(q5[..., None], shape),
            np.broadcast_to(q6[..., None], shape),
        ],
        axis=-1,
    ).reshape(n, 8, 6)
    valid = np.broadcast_to(ok1[:, None, None, None] & ok3[..., None], shape).reshape(n, 8)
    return wrap_pi(q), valid


def wrap_pi(q: FloatArray) -> FloatArray:
    """Angles wrapped into ``(-pi, pi]``."""
    return np.pi - np.mod(np.pi - q, 2.0 * np.pi)


def wrap_into_limits(
    q: FloatArray, lower: FloatArray, upper: FloatArray
) -> tuple[FloatArray, BoolArray]:
    """Shift each joint by a multiple of 2 pi (0, -2 pi or +2 pi) into ``[lower, upper]``.

    ``q`` has shape ``(..., 6)``; returns the shifted angles and a mask ``(...)`` that is True
    where every joint fits.
    """
    offsets = np.array([0.0, -2.0 * np.pi, 2.0 * np.pi])
    cand = q[..., None] + offsets  # (..., 6, 3)
    inside = (cand >= lower[:, None] - 1e-12) & (cand <= upper[:, None] + 1e-12)
    pick = np.argmax(inside, axis=-1)
    shifted = np.take_along_axis(cand, pick[..., None], axis=-1)[..., 0]
    ok = np.all(np.any(inside, axis=-1), axis=-1)
    return shifted, ok
