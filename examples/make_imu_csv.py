"""Write examples/imu.csv: 12 s of a simulated IMU at 50 Hz for `attitude ahrs`.

The attitude is closed form, q(t) = q_z(ψ) ⊗ q_x(θ) ⊗ q_y(γ) (the library's
z-x-y Euler angles, docs/conventions.md) with ψ, θ, γ at rest for 3 s, sinusoids
for 4 s, then at rest again; the gyro reads the body rate 2 q* ⊗ q̇ (q̇ by the product rule)
plus a 0.5 °/s bias on x and white noise, the accelerometer +9.81 m/s² up
and the magnetometer a 50 µT field with 63° dip, both rotated into the body,
with white noise. The reference columns qw..qz are q(t).

    python3 examples/make_imu_csv.py [PATH]     # rewrites examples/imu.csv (or writes PATH)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from attitude_c import reference as ref

RATE, SECONDS, REST, MOVE = 50.0, 12.0, 3.0, 4.0
#: Euler angle amplitudes (rad) and frequencies (Hz) after the rest: yaw, pitch, roll.
AMP, FREQ = np.array([1.2, 0.5, 0.7]), np.array([0.15, 0.4, 0.3])
FIELD_ENU = np.array([0.0, 22.7, -44.6])  # µT: 50 µT, dip 63°


def _angles(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Euler angles (N, 3) and their time derivatives."""
    s = np.clip(t - REST, 0.0, MOVE)[:, None]
    w = 2 * np.pi * FREQ
    return AMP * np.sin(w * s), np.where((s > 0) & (s < MOVE), AMP * w * np.cos(w * s), 0.0)


def _axis_q(axis: int, a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """q(a) about an axis and dq/da."""
    q, d = np.zeros(a.shape + (4,)), np.zeros(a.shape + (4,))
    q[:, 0], q[:, 1 + axis] = np.cos(a / 2), np.sin(a / 2)
    d[:, 0], d[:, 1 + axis] = -np.sin(a / 2) / 2, np.cos(a / 2) / 2
    return q, d


def recording(seed: int = 7) -> tuple[list[str], np.ndarray]:
    t = np.arange(int(SECONDS * RATE)) / RATE
    e, de = _angles(t)
    (qz, dz), (qx, dx), (qy, dy) = _axis_q(2, e[:, 0]), _axis_q(0, e[:, 1]), _axis_q(1, e[:, 2])
    m = ref.quat_multiply
    q = m(m(qz, qx), qy)
    qdot = (m(m(dz, qx), qy) * de[:, :1] + m(m(qz, dx), qy) * de[:, 1:2] + m(m(qz, qx), dy) * de[:, 2:])
    gyr = 2 * m(ref.quat_conj(q), qdot)[:, 1:]
    C = ref.quat_to_dcm(q)
    acc = np.einsum("nji,j->ni", C, [0.0, 0.0, 9.81])
    mag = np.einsum("nji,j->ni", C, FIELD_ENU)
    rng = np.random.default_rng(seed)
    gyr = gyr + np.radians([0.5, 0.0, 0.0]) + 0.003 * rng.standard_normal(gyr.shape)
    acc = acc + 0.03 * rng.standard_normal(acc.shape)
    mag = mag + 0.3 * rng.standard_normal(mag.shape)
    cols = "t,gx,gy,gz,ax,ay,az,mx,my,mz,qw,qx,qy,qz".split(",")
    return cols, np.column_stack([t, gyr, acc, mag, q])


def main() -> None:
    cols, table = recording()
    path = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).with_name("imu.csv")
    np.savetxt(path, table, delimiter=",", fmt="%.6g", comments="",
               header="# simulated IMU, 50 Hz: gyro rad/s, specific force m/s^2, field uT, reference "
               "quaternion body -> ENU (examples/make_imu_csv.py)\n" + ",".join(cols))


if __name__ == "__main__":
    main()
