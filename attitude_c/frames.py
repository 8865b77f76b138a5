"""Sensor mountings and Euler-angle sequences (docs/conventions.md, "Frames").

The library's body frame is x right, y forward, z up (RFU) and its
navigation frame ENU; its Euler angles are the z-x-y sequence
``C = R_z(ψ) R_x(θ) R_y(γ)``. Two things a user's IMU may need:

* :func:`axes_matrix`: an IMU mounted otherwise (x forward, y left, z up;
  x forward, y right, z down, ...) is described by where its x, y, z axes
  point, three letters of ``r l f b u d`` (right, left, forward, back, up,
  down): ``"flu"``, ``"frd"``, ``"rfu"`` (the library's own). The matrix
  ``R`` takes the IMU's vectors into the library's body frame,
  ``v_rfu = R v_imu``.
* :func:`euler`: yaw, pitch, roll of a quaternion in the library's z-x-y
  sequence (``"zxy"``) or in the aerospace z-y-x sequence (``"zyx"``): the
  attitude of the forward-right-down body in the north-east-down frame,
  ``C_frd^ned = R_z(ψ_a) R_y(θ_a) R_x(φ_a)``; yaw ψ_a is the heading,
  clockwise from north, pitch nose up, roll right wing down.

Relabelling the axes (``v_frd = M v_rfu``, ``v_ned = M v_enu`` with
``M = [[0,1,0],[1,0,0],[0,0,-1]]``) turns ``R_z(a)``, ``R_y(b)``, ``R_x(c)``
into ``R_z(−a)``, ``R_x(b)``, ``R_y(c)``: the two sequences describe the
same rotations, the aerospace pitch and roll equal the library's and the
aerospace yaw is −ψ. Near ±90° pitch the sequences differ only in which
angle takes the gimbal-lock rule (roll 0 in both).
"""

from __future__ import annotations

from typing import Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InvalidArgument

__all__ = ["AXES_PRESETS", "EulerSequence", "axes_matrix", "euler"]

FloatArray = NDArray[np.float64]

#: The Euler sequences :func:`euler` knows.
EulerSequence = Literal["zxy", "zyx"]

#: Unit vectors of the mounting letters in the library's body frame (x right, y forward, z up).
_DIRECTIONS = {"r": (1, 0, 0), "l": (-1, 0, 0), "f": (0, 1, 0), "b": (0, -1, 0), "u": (0, 0, 1),
               "d": (0, 0, -1)}

#: Common mountings: the library's own, x-forward/y-left/z-up (ROS, REP 103) and
#: x-forward/y-right/z-down (aerospace, NED-style body).
AXES_PRESETS = {"rfu": "x right, y forward, z up (the library's body frame)",
                "flu": "x forward, y left, z up",
                "frd": "x forward, y right, z down"}

#: FRD/NED axes from RFU/ENU axes (swap x and y, negate z): a proper rotation, its own inverse.
_M = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])

#: cos(pitch) below which the gimbal-lock rule applies, as the library's
#: att_dcm_to_euler in double (quat.h, ATT_GIMBAL_COS = 2^-26).
_GIMBAL_COS = 2.0 ** -26


def axes_matrix(spec: str) -> FloatArray:
    """``R`` (3, 3) with ``v_rfu = R v_imu`` for an IMU whose x, y, z axes point
    ``spec[0]``, ``spec[1]``, ``spec[2]`` (letters of ``rlfbud``, e.g. ``"flu"``)."""
    if not isinstance(spec, str) or len(spec) != 3 or any(c not in _DIRECTIONS for c in spec.lower()):
        raise InvalidArgument(f"axes: give three letters of r l f b u d (where the IMU's x, y, z point: "
                              f"right, left, forward, back, up, down), e.g. 'flu', got {spec!r}")
    R = np.array([_DIRECTIONS[c] for c in spec.lower()], dtype=np.float64).T
    det = float(np.linalg.det(R))
    if abs(det) < 0.5:
        raise InvalidArgument(f"axes: {spec!r} names one direction twice (each of x, y, z needs its own)")
    if det < 0:
        raise InvalidArgument(f"axes: {spec!r} is a left-handed frame (an IMU's axes are right-handed: "
                              "check the sign of one axis)")
    return R


def euler(q: ArrayLike, sequence: EulerSequence = "zxy") -> FloatArray:
    """Euler angles ``[yaw, pitch, roll]`` (…, 3), radians, of quaternions (…, 4)
    (body → ENU, scalar first) in ``sequence``: ``"zxy"`` the library's
    (:func:`attitude_c.quat_to_euler`), ``"zyx"`` the aerospace one (module doc)."""
    from .core import quat_to_dcm, quat_to_euler

    if sequence not in get_args(EulerSequence):
        raise InvalidArgument(f"sequence: choose from {', '.join(get_args(EulerSequence))}, got {sequence!r}")
    if sequence == "zxy":
        return np.asarray(quat_to_euler(q), dtype=np.float64)
    D = _M @ quat_to_dcm(q) @ _M  # C_frd^ned
    cp = np.hypot(D[..., 0, 0], D[..., 1, 0])
    lock = cp < _GIMBAL_COS
    pitch = np.arctan2(-D[..., 2, 0], cp)
    # at the lock only yaw ± roll is defined: roll 0, yaw from the first row's second column
    yaw = np.where(lock, np.arctan2(-D[..., 0, 1], D[..., 1, 1]), np.arctan2(D[..., 1, 0], D[..., 0, 0]))
    roll = np.where(lock, 0.0, np.arctan2(D[..., 2, 1], D[..., 2, 2]))
    out = np.stack([yaw, pitch, roll], axis=-1)
    return np.where(out <= -np.pi, np.pi, out)  # (−π, π], as the library's angles
