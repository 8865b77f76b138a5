"""Independent NumPy model of the MEMS AHRS paper's nine-state filter (docs/gnss-paper-filter.md), for tests.

Written from the error model in matrix form: the continuous A (9×9) is
assembled from its blocks — the skew matrix of the ENU specific force for
δV̇ = f × φ (its horizontal rows), −C_b^n for φ̇ = −C ε, −1/τ for the Markov
state — and discretized as Φ = I + A T with the Markov entry replaced by
its exact e^{−T/τ}; the GNSS update is one 2-row update with an explicit
H and ``numpy.linalg.solve``; the heading update the row H = e_φU − e_δψ.
The strapdown attitude uses the rv3-reuse rotation vector written from its
formula and ``reference.rotvec_to_quat``; heading from ``reference.heading``.
Not from the C source (which runs scalar sequential updates and
hand-expanded products). Slow (a Python loop per sample): for tests.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import reference as ref

__all__ = ["gnss9_reference"]

F = NDArray[np.float64]

_DEFAULTS: dict[str, float] = {
    "gravity": 9.80665, "gyr_noise": 1e-3, "drift_noise": 1e-5, "acc_noise": 0.02, "mag_tau": 300.0,
    "mag_sigma": 0.035, "gnss_vel_noise": 0.1, "heading_noise": 0.0175, "init_tilt_sigma": 0.035,
    "init_heading_sigma": 0.17, "init_vel_sigma": 0.5, "init_drift_sigma": 0.005, "max_gnss_age": 1.0,
    "kf_period": 5}

# state indices: δψ, δV (E, N), φ (E, N, U), ε (x, y, z)
PSI, DV, PHI, EPS = 0, slice(1, 3), slice(3, 6), slice(6, 9)


def _skew(a: F) -> F:
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def error_model(f_n: F, C: F, tau: float) -> F:
    """The continuous A of Ẋ = A X + W at ENU specific force f_n, attitude C."""
    A = np.zeros((9, 9))
    A[PSI, PSI] = -1.0 / tau
    A[DV, PHI] = _skew(f_n)[:2]  # δV̇ = f × φ = [f×] φ, rows E and N
    A[PHI, EPS] = -C
    return A


def _transition(f_n: F, C: F, T: float, tau: float) -> F:
    Phi = np.eye(9) + error_model(f_n, C, tau) * T
    Phi[PSI, PSI] = np.exp(-T / tau)
    return Phi


def _process_noise(T: float, s: dict[str, float]) -> F:
    d = np.empty(9)
    d[PSI] = s["mag_sigma"] ** 2 * (1.0 - np.exp(-2.0 * T / s["mag_tau"]))
    d[DV] = s["acc_noise"] ** 2 * T
    d[PHI] = s["gyr_noise"] ** 2 * T
    d[EPS] = s["drift_noise"] ** 2 * T
    return np.diag(d)


class _Model:
    def __init__(self, s: dict[str, float], q0: F, v0: F) -> None:
        self.s = s
        self.q = ref.quat_normalize(q0)
        self.v = np.array(v0, dtype=np.float64)
        self.eps = np.zeros(3)
        self.x = np.zeros(9)
        d = np.empty(9)
        d[PSI] = s["mag_sigma"] ** 2
        d[DV] = s["init_vel_sigma"] ** 2
        d[3:5] = s["init_tilt_sigma"] ** 2
        d[5] = s["init_heading_sigma"] ** 2
        d[EPS] = s["init_drift_sigma"] ** 2
        self.P = np.diag(d)
        self.incs: list[F] = []
        self.f_int, self.T, self.count = np.zeros(3), 0.0, 0
        self.acc_h = np.zeros(2)

    def rotation_vector(self, dth: F) -> F:
        """rv3-reuse: Φk = Δθk + (7/60) Δθk−1×Δθk − (1/60) Δθk−2×Δθk (start: Δθ1, then 1/12)."""
        prev = self.incs[-2:]
        self.incs = [*prev, dth]
        if not prev:
            return dth
        if len(prev) == 1:
            return dth + np.cross(prev[0], dth) / 12.0
        return dth + 7.0 / 60.0 * np.cross(prev[1], dth) - 1.0 / 60.0 * np.cross(prev[0], dth)

    def imu(self, w: F, f_b: F, h: float) -> None:
        step = ref.rotvec_to_quat(self.rotation_vector((w - self.eps) * h))
        self.q = ref.quat_normalize(ref.quat_multiply(self.q, step))
        f_n = ref.quat_to_dcm(self.q) @ f_b
        self.v = self.v + f_n[:2] * h
        self.acc_h = f_n[:2]
        self.f_int += f_n * h
        self.T += h
        self.count += 1
        if self.count >= self.s["kf_period"]:
            self.predict()

    def predict(self) -> None:
        if self.count == 0:
            return
        Phi = _transition(self.f_int / self.T, ref.quat_to_dcm(self.q), self.T, self.s["mag_tau"])
        self.x = Phi @ self.x
        self.P = Phi @ self.P @ Phi.T + _process_noise(self.T, self.s)
        self.f_int, self.T, self.count = np.zeros(3), 0.0, 0

    def update(self, H: F, z: F, R: F) -> None:
        S = H @ self.P @ H.T + R
        K = np.linalg.solve(S, H @ self.P).T
        self.x = self.x + K @ (z - H @ self.x)
        self.P = (np.eye(9) - K @ H) @ self.P
        self.q = ref.quat_normalize(ref.quat_multiply(ref.rotvec_to_quat(self.x[PHI]), self.q))
        self.v = self.v - self.x[DV]
        self.eps = self.eps + self.x[EPS]
        self.x[1:] = 0.0

    def gnss(self, vg: F, age: float) -> None:
        self.predict()
        H = np.zeros((2, 9))
        H[0, 1] = H[1, 2] = 1.0
        z = self.v - age * self.acc_h - vg
        self.update(H, z, self.s["gnss_vel_noise"] ** 2 * np.eye(2))

    def heading(self, psi_mag: float) -> None:
        self.predict()
        psi = float(ref.heading(self.q))
        z = (psi - psi_mag + np.pi) % (2 * np.pi) - np.pi
        H = np.zeros((1, 9))
        H[0, 5], H[0, PSI] = 1.0, -1.0
        self.update(H, np.array([z]), np.array([[self.s["heading_noise"] ** 2]]))


def gnss9_reference(gyr: ArrayLike, acc: ArrayLike, dt: float, gnss: dict[int, list[tuple[F, float]]] | None = None,
                    heading: ArrayLike | None = None, q0: ArrayLike = (1.0, 0.0, 0.0, 0.0),
                    v0: ArrayLike | None = None, **settings: Any) -> tuple[F, F, F]:
    """(N, 4) attitudes, (N, 2) velocities and the final drift (3,), from the
    initial attitude q0 (the C filter's coarse alignment is not modelled).

    ``gnss``: IMU sample index → [(v_gnss (2,), age)] applied after it, then
    ``heading[k]`` when finite. Settings: the C field names (ahrs_gnss9.h)."""
    s = dict(_DEFAULTS)
    s.update(settings)
    g, a = np.asarray(gyr, dtype=np.float64), np.asarray(acc, dtype=np.float64)
    m = _Model(s, np.asarray(q0, dtype=np.float64),
               np.zeros(2) if v0 is None else np.asarray(v0, dtype=np.float64))
    hd = None if heading is None else np.asarray(heading, dtype=np.float64)
    qs, vs = np.empty((g.shape[0], 4)), np.empty((g.shape[0], 2))
    for k in range(g.shape[0]):
        m.imu(g[k], a[k], float(dt))
        for vg, age in (gnss or {}).get(k, []):
            m.gnss(np.asarray(vg, dtype=np.float64)[:2], age)
        if hd is not None and np.isfinite(hd[k]):
            m.heading(float(hd[k]))
        qs[k], vs[k] = m.q, m.v
    return qs, vs, m.eps
