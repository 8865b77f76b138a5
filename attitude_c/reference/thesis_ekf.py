"""Independent NumPy model of the UAV thesis's EKF (docs/ahrs.md, "The thesis's EKF"), for tests.

Written from the thesis's equations (sec. 3.2.3, eq. 3.45–3.57) in matrix
form: the 7×7 Φ = I + F h with F's blocks built column by column from
quaternion products (``reference.quat_multiply``), P ← Φ P Φᵀ + Q, the gain
K = P Hᵀ (H P Hᵀ + R)⁻¹ by ``numpy.linalg.solve`` with an explicit H = [I₄ 0],
the Joseph form; the measurement from the NumPy Gauss–Newton
(``reference.aiding.gauss_newton``), the first attitude from
``reference.aiding.align``. Not from the C source (hand-expanded products,
a Cholesky solve). Slow (a Python loop per sample): for differential tests.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import reference as ref
from . import aiding as refaid

__all__ = ["thesis_ekf_reference"]

F = NDArray[np.float64]

_DEFAULTS: dict[str, float] = {"gyr_noise": 0.01, "bias_noise": 0.0, "meas_noise": 0.025,
                               "init_q_sigma": 0.05, "init_bias_sigma": 0.03, "declination": 0.0}


def _pure(w: F) -> F:
    return np.concatenate([[0.0], w])


def _omega(w: F) -> F:
    """Ω(w) with Ω(w) q = q ⊗ [0, w]: column i is e_i ⊗ [0, w]."""
    return np.stack([ref.quat_multiply(np.eye(4)[i], _pure(w)) for i in range(4)], axis=1)


def _xi(q: F) -> F:
    """Ξ(q) with Ξ(q) w = q ⊗ [0, w]: column j is q ⊗ [0, e_j]."""
    return np.stack([ref.quat_multiply(q, _pure(np.eye(3)[j])) for j in range(3)], axis=1)


def _qdot(q: F, w: F) -> F:
    """Right-hand side of q̇ = ½ q ⊗ [0, w] (eq. 3.12 in the body → nav convention)."""
    return 0.5 * np.asarray(ref.quat_multiply(q, _pure(w)))


def thesis_ekf_reference(gyr: ArrayLike, acc: ArrayLike, mag: ArrayLike, dt: float,
                         q0: ArrayLike | None = None, **settings: Any) -> tuple[F, F, int]:
    """(N, 4) attitudes, the final bias (3,) and the number of skipped
    measurement updates. Settings: the C field names (ahrs_thesis.h)."""
    s = dict(_DEFAULTS)
    s.update(settings)
    g = np.asarray(gyr, dtype=np.float64)
    a = np.asarray(acc, dtype=np.float64)
    m = np.asarray(mag, dtype=np.float64)
    n = g.shape[0]
    h = float(dt)
    x = np.zeros(7)
    P = np.diag([s["init_q_sigma"] ** 2] * 4 + [s["init_bias_sigma"] ** 2] * 3)
    H = np.hstack([np.eye(4), np.zeros((4, 3))])
    R = s["meas_noise"] ** 2 / h * np.eye(4)
    Qb = s["bias_noise"] ** 2 * h * np.eye(3)
    out = np.empty((n, 4))
    skipped = 0
    k0 = 0
    if q0 is None:
        x[:4] = refaid.align(a[0], m[0], s["declination"])
        out[0] = x[:4]
        k0 = 1
    else:
        x[:4] = np.asarray(q0, dtype=np.float64) / np.linalg.norm(q0)
    prev = g[0] if q0 is None else None
    for k in range(k0, n):
        q, b = x[:4].copy(), x[4:].copy()
        wp = g[k] if prev is None else prev
        w0, w1, w2 = wp - b, 0.5 * (wp + g[k]) - b, g[k] - b
        # Φ = I + F h at X_{k-1}; F = ∂/∂X [½ q ⊗ (ω − b); 0]
        Fm = np.zeros((7, 7))
        Fm[:4, :4] = 0.5 * _omega(w1)
        Fm[:4, 4:] = -0.5 * _xi(q)
        Phi = np.eye(7) + Fm * h
        G = -0.5 * _xi(q)                      # the gyro's white noise into q̇
        Q = np.zeros((7, 7))
        Q[:4, :4] = s["gyr_noise"] ** 2 * h * G @ G.T
        Q[4:, 4:] = Qb
        P = Phi @ P @ Phi.T + Q
        # RK4 (eq. 3.21): rates at t, t + h/2, t + h
        k1 = h * _qdot(q, w0)
        k2 = h * _qdot(q + k1 / 2, w1)
        k3 = h * _qdot(q + k2 / 2, w1)
        k4 = h * _qdot(q + k3, w2)
        qp = q + (k1 + 2 * k2 + 2 * k3 + k4) / 6
        qp = qp / np.linalg.norm(qp)
        x = np.concatenate([qp, b])
        # warm start at the prediction: Newton converges in ≤ 6 steps (quadratically)
        z, ok = refaid.gauss_newton(a[k], m[k], qp, s["declination"], iterations=10)
        if bool(ok):
            z = np.asarray(z, dtype=np.float64)
            if z @ qp < 0:
                z = -z
            S = H @ P @ H.T + R
            K = np.linalg.solve(S, H @ P).T   # S symmetric: K = P Hᵀ S⁻¹
            x = x + K @ (z - H @ x)
            A = np.eye(7) - K @ H
            P = A @ P @ A.T + K @ R @ K.T
            x[:4] = x[:4] / np.linalg.norm(x[:4])
        else:
            skipped += 1
        out[k] = x[:4]
        prev = g[k]
    return out, x[4:].copy(), skipped
