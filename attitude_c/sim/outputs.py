"""Stage 9 of the simulator (docs/architecture.md): the outputs.

The estimated attitude against the truth at the same times: Euler angles of
both (the library's ``att_quat_to_euler`` for the estimate; the trajectory's
own for the truth), their wrapped differences, the angle of the rotation
between the two attitudes (the library's product and rotation vector), and
the error statistics of the summary.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core import quat_conj, quat_multiply, quat_to_euler, quat_to_rotvec
from .estimator import Estimate
from .trajectory import Trajectory

__all__ = ["Errors", "attitude_angle", "compare", "stats", "wrap_angle"]


def wrap_angle(a: np.ndarray) -> np.ndarray:
    """Wrap to (−π, π]."""
    a = np.asarray(a, dtype=float)
    w = np.mod(a + np.pi, 2 * np.pi) - np.pi
    return np.where(w == -np.pi, np.pi, w)


def attitude_angle(qa: np.ndarray, qb: np.ndarray) -> np.ndarray:
    """Angle (rad, [0, π]) of the rotation taking attitude qa to qb (the library's math)."""
    qa, qb = np.asarray(qa, dtype=float), np.asarray(qb, dtype=float)
    if qa.size == 0:
        return np.zeros(qa.shape[:-1])
    return np.linalg.norm(quat_to_rotvec(quat_multiply(quat_conj(qa), qb)), axis=-1)


def stats(e: np.ndarray) -> dict[str, float]:
    """max, min, RMS and max |e| of an error series (zeros when empty)."""
    if e.size == 0:
        return {"max": 0.0, "min": 0.0, "rms": 0.0, "max_abs": 0.0}
    return {"max": float(np.max(e)), "min": float(np.min(e)),
            "rms": float(np.sqrt(np.mean(e * e))), "max_abs": float(np.max(np.abs(e)))}


@dataclass
class Errors:
    """Truth and estimate at the estimate's times ``t`` (M,): quaternions (M, 4),
    Euler angles ``[yaw, pitch, roll]`` (M, 3), wrapped differences ``err``
    (M, 3) and the attitude angle ``err_angle`` (M,)."""

    t: np.ndarray
    q_est: np.ndarray
    q_true: np.ndarray
    euler_est: np.ndarray
    euler_true: np.ndarray
    err: np.ndarray
    err_angle: np.ndarray

    def summary(self) -> dict[str, Any]:
        """Error statistics per angle (heading = −yaw) and of the attitude angle (rad)."""
        return {"heading": stats(-self.err[:, 0]), "yaw": stats(self.err[:, 0]), "pitch": stats(self.err[:, 1]),
                "roll": stats(self.err[:, 2]), "attitude_angle": stats(self.err_angle)}


def compare(estimate: Estimate, traj: Trajectory) -> Errors:
    """The estimate against the trajectory's truth at the estimate's times."""
    t, q_est = estimate.t, estimate.q
    q_true = traj.quat(t)
    e_est = quat_to_euler(q_est) if len(q_est) else np.zeros((0, 3))
    e_true = traj.euler(t) if len(t) else np.zeros((0, 3))
    err = wrap_angle(e_est - e_true)
    return Errors(t, q_est, q_true, e_est, e_true, err, attitude_angle(q_true, q_est))
