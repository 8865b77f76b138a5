"""Independent NumPy model of the attitude filter (docs/ahrs.md), for tests.

Written from the filter's equations in matrix form — the full 6×6
transition F = [[I, −C dt], [0, I]], P ← F P Fᵀ + Q, scalar updates with an
explicit selector row H, masked gain K and the Joseph form
P ← (I − K H) P (I − K H)ᵀ + K R Kᵀ, the attitude as an exactly normalized
quaternion product — not from the C source, which works on 3×3 blocks and
hand-expanded products. Slow (a Python loop per sample): for differential
tests on short records, never for production use.

Inputs as :func:`attitude_c.ahrs_filter.ahrs`; settings as a dict with the C
field names (``method`` by name).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import reference as ref

__all__ = ["ReferenceAhrs", "ahrs_reference"]

F = NDArray[np.float64]

_DEFAULTS: dict[str, Any] = {
    "method": "rv3-reuse", "gravity": 9.81, "gyr_noise": 0.01, "gyr_noise_rest": 0.002,
    "bias_noise": 1e-4, "init_att_sigma": 0.1, "init_bias_sigma": 0.01, "acc_tau": 2.0, "acc_noise": 0.025,
    "acc_gate": 0.2, "acc_reject_max": 3.0, "mag_noise": 0.1, "mag_norm_tol": 0.08,
    "mag_dip_tol": 0.17, "mag_ref_tau": 30.0, "mag_ref_window": 5.0, "mag_reject_max": 60.0, "mag_reject_factor": 2.0,
    "mag_new_time": 20.0, "mag_new_gyr": 0.35, "mag_min_undisturbed": 0.5, "declination": 0.0,
    "rest_time": 1.5, "rest_tau": 0.5, "rest_gyr_th": 0.035, "rest_acc_th": 0.5,
    "rest_noise": 3e-4, "gyro_range": 0.0, "overrange_sigma": 0.05, "sensor_delay": 0.0,
    "acc_delay": 0.0, "mag_delay": 0.0, "tilt_tau": 3.0, "heading_sigma_max": 0.0873,
    "turn_sigma": 0.002, "turn_tau": 5.0,
    "gnss_vel_sigma": 0.2, "gnss_timeout": 3.0, "gnss_max_latency": 1.0, "gnss_max_pdop": 10.0,
    "gnss_max_sigma": 2.0, "gnss_max_acc": 40.0, "gnss_gate": 5.0, "gnss_window": 0.9, "gnss_gyr_noise": 0.002,
}

#: Entries of the GNSS history (ahrs.h, ATT_AHRS_GNSS_HIST: part of the documented behaviour,
#: since a velocity's integral is interpolated between them).
GNSS_HIST = 24

_FRAME = {"rv1": 1, "rv2": 2, "rv3": 3, "rv3-coning": 3, "rv3-reuse": 1, "rv3-reuse-poly": 1}


def _qmul(a: F, b: F) -> F:
    return np.asarray(ref.quat_multiply(a, b), dtype=np.float64)


def _exp(phi: F) -> F:
    """Unit quaternion of rotation vector phi (eq. 3), from sin and cos."""
    a = float(np.linalg.norm(phi))
    if a == 0.0:
        return np.array([1.0, 0.0, 0.0, 0.0])
    return np.concatenate([[math.cos(a / 2)], math.sin(a / 2) / a * phi])


def _skew(v: F) -> F:
    """[v×], the matrix of the cross product v × ·."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _undelay(x: F, rate: F, d: float) -> F:
    """A body-frame sample x taken d seconds before the gyro's, seen at the gyro's time.

    A navigation-fixed vector seen from the body obeys ẋ = −[ω×] x, so over d at constant
    rate x(t) = exp(−[θ×]) x(t − d), θ = ω d; kept to second order, (I − W + W²/2) x with
    W = [θ×] (the remainder is the series' cubic term and beyond: ≤ |θ|³/6·|x| to leading order).
    """
    if d == 0.0:
        return x
    W = _skew(rate * d)
    return (np.eye(3) - W + 0.5 * (W @ W)) @ x


def _tilt_step(z: F, fnav: F, dt: float, tau: float) -> F:
    """One step of the reported inclination's low-pass (docs/ahrs.md, "Reported inclination").

    Per axis the second-order system f̈ + 2ζω0 ḟ + ω0² f = ω0² a, ζ = 1/√2, ω0 = √2/τ,
    written as ż = A z + B a with z = (f, ḟ); implicit Euler: (I − dt A) z⁺ = z + dt B a,
    solved as a linear system. z is (2, 3): row 0 the filtered vector, row 1 its rate.
    """
    w0 = math.sqrt(2.0) / tau
    zeta = 1.0 / math.sqrt(2.0)
    A = np.array([[0.0, 1.0], [-w0 * w0, -2.0 * zeta * w0]])
    B = np.array([[0.0], [w0 * w0]])
    return np.asarray(np.linalg.solve(np.eye(2) - dt * A, z + dt * B @ fnav[None, :]), dtype=np.float64)


def _level(q: F, f: F) -> F:
    """q turned by the smallest rotation that takes the navigation-frame vector f to up
    (rotation vector along f × e_z, angle between f and e_z), while f is above the horizon."""
    v = f / np.linalg.norm(f)
    if v[2] <= 0.0:
        return q
    axis = np.cross(v, [0.0, 0.0, 1.0])
    s = float(np.linalg.norm(axis))
    if s == 0.0:
        return q
    return _qmul(_exp(axis / s * math.atan2(s, float(v[2]))), q)


def _dcm(q: F) -> F:
    return np.asarray(ref.quat_to_dcm(q / np.linalg.norm(q)), dtype=np.float64)


def _align(f: F, m: F | None, decl: float) -> F:
    """Attitude from gravity (up) and the field (north), TRIAD form: the
    navigation axes expressed in the body are the rows of C_b^n."""
    up = f / np.linalg.norm(f)
    east = None
    if m is not None:
        e = np.cross(m, up)
        if np.linalg.norm(e) > 1e-4 * np.linalg.norm(m):
            east = e / np.linalg.norm(e)
    if east is None:  # heading 0: yaw ψ = 0 of the z-x-y Euler angles
        theta = math.atan2(f[1], math.hypot(f[0], f[2]))
        gamma = math.atan2(-f[0], f[2])
        return np.asarray(ref.euler_to_quat(np.array([0.0, theta, gamma])), dtype=np.float64)
    north = np.cross(up, east)
    Cm = np.vstack([east, north, up])  # magnetic-north navigation frame
    c, s = math.cos(-decl), math.sin(-decl)
    Rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return np.asarray(ref.dcm_to_quat(Rz @ Cm), dtype=np.float64)


class ReferenceAhrs:
    """One filter state; :meth:`update` takes one sample."""

    def __init__(self, q0: ArrayLike | None = None, **settings: Any) -> None:
        self.s = dict(_DEFAULTS)
        self.s.update(settings)
        self.q = None if q0 is None else np.asarray(q0, float) / np.linalg.norm(q0)
        self.b = np.zeros(3)
        va, vb = self.s["init_att_sigma"] ** 2, self.s["init_bias_sigma"] ** 2
        self.P = np.diag([va, va, va, vb, vb, vb]).astype(float)
        self.hist: list[F] = []
        self.n_inc = 0
        self.acc_lp: F | None = None
        self.acc_norm_lp = 0.0
        self.acc_rej = 0.0
        self.mag_ref: F | None = None
        self.mag_ref_w = 0.0  # the weight (s) each field estimate holds
        self.mag_cand = np.zeros(2)
        self.mag_cand_w = 0.0
        self.mag_cand_t = 0.0
        self.mag_undist = 0.0
        self.mag_rej = 0.0
        self.rest_g: F | None = None
        self.rest_a = np.zeros(3)
        self.rest_t = 0.0
        self.tilt: F | None = None  # (2, 3): tilt_tau's low-pass of the specific force and its rate
        # the start: the samples so far (each carried through the corrections since) and their dt
        self.tilt_start: F | None = np.zeros((0, 3))
        self.tilt_dts: list[float] = []
        self.flags = 0
        self.heading_measured = False  # a magnetometer update has been made
        self.turn_var = 0.0  # rad², added to the reported attitude covariance
        self.gnss = _GnssState()
        self.mag_spread = 0.0  # the accepted fields' mean (|m|/norm − 1)², norm the reference's
        self.mag_dspread = 0.0  # ... and of half the squared step between accepted samples' |m|/norm
        self.mag_prev: float | None = None  # the last accepted sample's |m|
        self.last_dt = 0.0  # s, the last update's step

    @property
    def covariance(self) -> F:
        """The reported attitude covariance: P's attitude block plus the turn variance on its
        diagonal (rad², the ENU rotation vector δθ, q_true = exp(δθ) ⊗ q), plus the field's term
        on the heading: a disturbance of the field that turns it about the vertical leaves its
        norm and dip as they are, so that unseen component is given the variance of the seen
        relative norm deviation, s², and turns the horizontal field, of size |m| cos(dip), by
        s / cos(dip) rad. The white part of s² (the magnetometer's noise, already in the heading's
        R) is left out: for white noise half the mean squared step between samples is its variance
        (the Allan variance at one sample), for a slow disturbance that is small."""
        c = self.P[:3, :3] + self.turn_var * np.eye(3)
        if self.mag_ref is not None:
            # less twice the 1σ of (spread − white part) for white noise over N = W/dt samples,
            # white part/√N: a spread that is noise alone gives no term
            white = self.mag_dspread * (1.0 + 2.0 * math.sqrt(self.last_dt / self.mag_ref_w))
            c[2, 2] += max(self.mag_spread - white, 0.0) / max(math.cos(float(self.mag_ref[1])) ** 2, 1e-6)
        return c

    @property
    def bias_covariance(self) -> F:
        return self.P[3:, 3:].copy()

    # -- the Kalman pieces -------------------------------------------------
    def _predict(self, C: F, dt: float, rest: bool, rate: F, aided: bool = False) -> None:
        """Q: the attitude's process noise density is the gyro's own at rest (no motion,
        no model error: ``gyr_noise_rest``), ``gnss_gyr_noise`` while GNSS-aided, ``gyr_noise``
        (gyro noise + model error) otherwise.
        Beside P, the reported turn variance: a first-order lag (time constant ``turn_tau``,
        implicit Euler) driven by (``turn_sigma`` · |ω − b|)² · dt."""
        Fm = np.eye(6)
        Fm[:3, 3:] = -C * dt
        sg = self.s["gyr_noise_rest"] if rest else self.s["gnss_gyr_noise"] if aided else self.s["gyr_noise"]
        Q = np.diag([sg ** 2 * dt] * 3 + [self.s["bias_noise"] ** 2 * dt] * 3)
        tau = self.s["turn_tau"]
        self.turn_var = self.turn_var * tau / (tau + dt) + (self.s["turn_sigma"] * float(np.linalg.norm(rate))) ** 2 * dt
        self.P = Fm @ self.P @ Fm.T + Q

    def _scalar(self, x: F, j: int, y: float, R: float, states: tuple[int, ...]) -> None:
        H = np.zeros((1, 6))
        H[0, j] = 1.0
        S = float((H @ self.P @ H.T)[0, 0]) + R
        K = (self.P @ H.T)[:, 0] / S
        keep = np.zeros(6)
        keep[list(states)] = 1.0
        K = K * keep
        x += K * (y - float((H @ x)[0]))
        A = np.eye(6) - np.outer(K, H[0])
        self.P = A @ self.P @ A.T + R * np.outer(K, K)

    # -- the magnetic reference ---------------------------------------------
    def _agrees(self, est: F, cur: F) -> bool:
        s = self.s
        return bool(abs(cur[0] - est[0]) <= s["mag_norm_tol"] * est[0] and abs(cur[1] - est[1]) <= s["mag_dip_tol"])

    def _weight(self, dt: float) -> float:
        """A field sample's weight: dt times the share its dip keeps of the information
        when the inclination's variance P_xx + P_yy adds to the variance (mag_dip_tol/2)²."""
        v = (self.s["mag_dip_tol"] / 2) ** 2
        return dt * v / (v + self.P[0, 0] + self.P[1, 1])

    def _learn(self, est: F, weight: float, cur: F, w: float) -> tuple[F, float]:
        """Weighted running mean of (norm, dip) whose weight stops growing at mag_ref_tau."""
        total = min(weight + w, self.s["mag_ref_tau"])
        return est + (w / total) * (cur - est), total

    def _mag_reference(self, cur: F, gyr: F, dt: float) -> tuple[bool, float, int]:
        """The reference and candidate against one field sample cur = (norm, dip): (use it, its R, flags)."""
        s = self.s
        R = s["mag_noise"] ** 2 / dt
        w = self._weight(dt)
        if self.mag_ref is None:  # the first sample starts both
            self.mag_ref, self.mag_ref_w = cur.copy(), w
            self.mag_spread, self.mag_dspread, self.mag_prev = 0.0, 0.0, None
            self.mag_cand, self.mag_cand_w, self.mag_cand_t = cur.copy(), w, 0.0
            self.mag_undist = s["mag_min_undisturbed"]
        elif self._agrees(self.mag_cand, cur):
            self.mag_cand, self.mag_cand_w = self._learn(self.mag_cand, self.mag_cand_w, cur, w)
            if float(np.sum(gyr * gyr)) >= s["mag_new_gyr"] ** 2:
                self.mag_cand_t += dt
        else:
            self.mag_cand, self.mag_cand_w, self.mag_cand_t = cur.copy(), w, 0.0
        if self._agrees(self.mag_ref, cur):
            self.mag_ref, self.mag_ref_w = self._learn(self.mag_ref, self.mag_ref_w, cur, w)
            self.mag_undist += dt
            if self.mag_undist >= s["mag_min_undisturbed"]:
                # the spread of the samples the heading uses: the same weighted mean, of the
                # squared deviation from the new reference and of half the squared step
                d2 = (cur[0] / self.mag_ref[0] - 1.0) ** 2
                self.mag_spread += (w / self.mag_ref_w) * (d2 - self.mag_spread)
                if self.mag_prev is not None:
                    e2 = ((cur[0] - self.mag_prev) / self.mag_ref[0]) ** 2 / 2
                    self.mag_dspread += (w / self.mag_ref_w) * (e2 - self.mag_dspread)
                self.mag_prev = float(cur[0])
                self.mag_rej = 0.0
                return True, R, 0
            self.mag_rej += dt
            return False, R, 8
        if self.mag_ref_w < s["mag_ref_window"]:  # not established yet: it starts again here
            self.mag_ref, self.mag_ref_w = cur.copy(), w
            self.mag_rej, self.mag_undist = 0.0, s["mag_min_undisturbed"]
            self.mag_spread, self.mag_dspread, self.mag_prev = 0.0, 0.0, None
            return True, R, 0
        if self.mag_cand_t >= s["mag_new_time"]:  # a new homogeneous field
            self.mag_ref, self.mag_ref_w = self.mag_cand.copy(), self.mag_cand_w
            self.mag_rej, self.mag_undist = 0.0, s["mag_min_undisturbed"]
            self.mag_spread, self.mag_dspread, self.mag_prev = 0.0, 0.0, None
            return True, R, 16
        self.mag_undist = 0.0
        self.mag_rej += dt
        if self.mag_rej >= s["mag_reject_max"]:  # bounded rejection: weak updates
            return True, R * s["mag_reject_factor"] ** 2, 8
        return False, R, 8

    # -- one sample --------------------------------------------------------
    def update(self, gyr: ArrayLike, acc: ArrayLike, mag: ArrayLike | None, dt: float) -> F:
        s = self.s
        self.last_dt = dt
        w = np.asarray(gyr, float)
        f = np.asarray(acc, float)
        m = None if mag is None else np.asarray(mag, float)
        g = s["gravity"]
        fn = float(np.linalg.norm(f))
        if self.acc_lp is None and not (0.25 * g <= fn <= 4.0 * g):
            raise ValueError("units")
        if self.q is None:
            self.q = _align(f, m, s["declination"])
        flags = 0
        if s["gyro_range"] > 0 and np.any(np.abs(w) >= s["gyro_range"]):
            flags |= 1
        # rest detector
        rest = False
        if s["rest_time"] > 0:
            if self.rest_g is None:
                self.rest_g, self.rest_a, self.rest_t = w.copy(), f.copy(), 0.0
            else:
                k = dt / (s["rest_tau"] + dt)
                self.rest_g = self.rest_g + k * (w - self.rest_g)
                self.rest_a = self.rest_a + k * (f - self.rest_a)
                th = s["rest_gyr_th"] ** 2
                still = (np.sum((w - self.rest_g) ** 2) < th and np.sum((self.rest_g - self.b) ** 2) < th
                         and np.sum((f - self.rest_a) ** 2) < s["rest_acc_th"] ** 2)
                self.rest_t = self.rest_t + dt if still else 0.0
                rest = self.rest_t >= s["rest_time"]
        # propagation
        method = s["method"]
        mf = _FRAME[method]
        self.hist = (self.hist + [(w - self.b) * dt])[-3:]
        self.n_inc += 1
        if self.n_inc % mf == 0:  # an update completes (every increment for rv1 and the reuse forms)
            phi = ref.rotation_vectors(np.array(self.hist[-3:] if mf == 1 else self.hist[-mf:]), method)[-1]
            self.q = _qmul(self.q, _exp(phi))
            self.q = self.q / np.linalg.norm(self.q)
        C = _dcm(self.q)
        gs = self.gnss
        aided = gs.used and gs.time + dt - gs.used_t <= s["gnss_timeout"]
        self._predict(C, dt, rest, w - self.b, aided)
        if flags & 1:
            self.P[:3, :3] += s["overrange_sigma"] ** 2 * np.eye(3)
        x = np.zeros(6)
        if gs.aided and not aided and s["tilt_tau"] > 0:
            # back to the accelerometer: the reported inclination's low-pass continues from the
            # state's own (the vertical, at rest), as if converged
            self.tilt, self.tilt_start = np.array([[0.0, 0.0, s["gravity"]], [0.0, 0.0, 0.0]]), None
        # accelerometer
        wc = w - self.b  # the rate the propagation used (the bias before this sample's update)
        fnav = C @ _undelay(f, wc, s["acc_delay"])
        if self.acc_lp is None:
            self.acc_lp, self.acc_norm_lp = fnav, fn
        else:
            a = dt / (s["acc_tau"] + dt) if s["acc_tau"] > 0 else 1.0
            self.acc_lp = self.acc_lp + a * (fnav - self.acc_lp)
            self.acc_norm_lp += dt / (10.0 + dt) * (fn - self.acc_norm_lp)
        v = self.acc_lp / np.linalg.norm(self.acc_lp)
        axis = np.cross(v, [0.0, 0.0, 1.0])  # rotation taking v to up
        ang = math.atan2(float(np.linalg.norm(axis)), float(v[2]))
        y = axis / np.linalg.norm(axis) * ang if np.linalg.norm(axis) > 0 else np.zeros(3)
        use = True
        if aided:  # the inclination comes from the GNSS velocities
            use, self.acc_rej = False, 0.0
        elif s["acc_gate"] > 0 and ang > s["acc_gate"]:
            self.acc_rej += dt
            if self.acc_rej < s["acc_reject_max"]:
                use = False
                flags |= 4
            else:
                self.acc_rej = 0.0
        else:
            self.acc_rej = 0.0
        if use:
            R = s["acc_noise"] ** 2 / dt
            for j in (0, 1):
                self._scalar(x, j, float(y[j]), R, (0, 1, 3, 4, 5))
            if s["tilt_tau"] > 0:
                # at rest the time constant grows as the state's does (no model error)
                tau = s["tilt_tau"] * (s["gyr_noise"] / s["gyr_noise_rest"] if rest else 1.0)
                if self.tilt_start is not None:  # the start: the plain mean until it spans τ
                    self.tilt_start = np.vstack([self.tilt_start, fnav])
                    self.tilt_dts.append(dt)
                    span = sum(self.tilt_dts)
                    mean = np.asarray(self.tilt_dts) @ self.tilt_start / span
                    self.tilt = np.vstack([mean, np.zeros(3)])
                    if span >= tau:
                        self.tilt_start = None
                else:
                    assert self.tilt is not None
                    self.tilt = _tilt_step(self.tilt, fnav, dt, tau)
        # magnetometer
        if m is not None:
            mn = C @ _undelay(m, wc, s["mag_delay"])
            h = math.hypot(mn[0], mn[1])
            if h > 0:
                cur = np.array([float(np.linalg.norm(mn)), math.atan2(-mn[2], h)])
                use, R, mflags = self._mag_reference(cur, w, dt)  # w: the gyro sample
                flags |= mflags
                if use:
                    yh = math.atan2(mn[0], mn[1]) - s["declination"]
                    yh = (yh + math.pi) % (2 * math.pi) - math.pi
                    # the field's heading in the estimate's frame: an error δθ turns the field
                    # by −δθ × m, whose horizontal part across the field is h·(δθz + tan(dip)·δθ·u)
                    # with u the horizontal field's direction (magnetic north)
                    u = np.array([mn[0], mn[1], 0.0]) / h
                    row = np.concatenate([math.tan(float(cur[1])) * u + np.array([0.0, 0.0, 1.0]), np.zeros(3)])
                    self._row(x, row, yh, R, (2, 3, 4, 5))
                    self.heading_measured = True
        if rest:
            flags |= 2
            assert self.rest_g is not None
            for i in range(3):
                self._scalar(x, 3 + i, float(self.rest_g[i] - self.b[i]), s["rest_noise"] ** 2 / dt,
                             (3, 4, 5))
        self._inject(x)
        # heading observability: measured at least once, and its 1σ within the bound since
        # (P and the turn term: the field's term does not grow while the heading goes unmeasured)
        if not (self.heading_measured and self.P[2, 2] + self.turn_var <= s["heading_sigma_max"] ** 2):
            flags |= 32
        self.flags = flags | (64 if aided else 0) | (128 if gs.rejected else 0)
        gs.record(fnav, dt, g, aided, s["gnss_max_latency"] / (GNSS_HIST - 2))
        out = self.reported()
        if s["sensor_delay"]:
            return _qmul(out, _exp((w - self.b) * s["sensor_delay"]))
        return out

    def reported(self) -> F:
        """The reported attitude: the state's, levelled by the tilt_tau low-pass when on."""
        assert self.q is not None
        if self.tilt is None or self.gnss.aided:
            return self.q.copy()
        return _level(self.q, self.tilt[0])

    # -- GNSS velocity aiding (docs/ahrs.md, "GNSS velocity aiding") ----------
    def update_vel(self, t: float, vel: ArrayLike, sigma: float = 0.0, pdop: float = 0.0, has_up: bool = False,
                   fix_type: int = 3) -> None:
        """One GNSS velocity (ENU, m/s) valid at ``t`` on the filter's clock; ValueError where the
        C function returns ATT_E_ARG."""
        s, gs = self.s, self.gnss
        v = np.zeros(3)
        v[:3 if has_up else 2] = np.asarray(vel, float)[:3 if has_up else 2]
        step = gs.last_dt
        if sigma < 0 or pdop < 0 or t > gs.time + step or t < gs.time - s["gnss_max_latency"] or (
                gs.anchor is not None and t <= gs.anchor[0]):
            raise ValueError("t, sigma or pdop outside the domain")
        if self.q is None:
            return
        if not gs.armed:
            gs.arm()
            return
        sig = sigma if sigma > 0 else s["gnss_vel_sigma"]
        if (fix_type not in (2, 3, 4) or (s["gnss_max_pdop"] > 0 and pdop > s["gnss_max_pdop"])
                or (s["gnss_max_sigma"] > 0 and sig > s["gnss_max_sigma"])):
            gs.rejected = True
            return
        sv_t = gs.integral_at(t)
        if sv_t is None:
            return
        if gs.anchor is None or t - gs.anchor[0] > s["gnss_timeout"]:
            gs.set_anchor(t, sv_t, v, sig ** 2, has_up, np.zeros(3), s["gravity"])
            return
        if t - gs.anchor[0] < s["gnss_window"]:  # too close to the anchor: skipped
            return
        self._gnss_compare(t, sv_t, v, sig ** 2, has_up)

    def _gnss_rows(self, dS: F, dv: F, dT: float, tau: float, up: bool, heading: bool,
                   R: float) -> list[tuple[F, float]]:
        """(h, y) rows of r = Δv − ΔS = −[ΔF×] δθ(t_m), δθ(t_m) = δθ + C τ δb, ΔF = ΔS + g Δt e_z."""
        assert self.q is not None
        Fv = dS + np.array([0.0, 0.0, self.s["gravity"] * dT])
        Hfull = np.asarray(np.hstack([-_skew(Fv), -_skew(Fv) @ _dcm(self.q) * tau]), dtype=np.float64)  # 3×6
        r = dv - dS
        nv, ns = math.hypot(dv[0], dv[1]), math.hypot(dS[0], dS[1])
        if not heading and ns > 0 and nv * nv > 9 * R:  # compare the horizontal lengths along ΔS_h
            u = np.array([dS[0] / ns, dS[1] / ns, 0.0])
            rows = [(u @ Hfull, nv - ns)]
        else:
            rows = [(Hfull[i], float(r[i])) for i in (0, 1)]
        if up:
            rows.append((Hfull[2], float(r[2])))
        if not heading:
            rows = [(np.where(np.arange(6) == 2, 0.0, h), y) for h, y in rows]
        return rows

    def _gnss_compare(self, t: float, sv_t: F, v: F, var: float, has_up: bool) -> None:
        s, gs = self.s, self.gnss
        assert gs.anchor is not None and self.q is not None
        t_a, s_a, v_a, var_a, up_a = gs.anchor
        dS, dv, dT = sv_t - s_a, v - v_a, t - t_a
        heading = not self.flags & 32
        R = var + var_a
        rows = self._gnss_rows(dS, dv, dT, gs.time - (t + t_a) / 2, has_up and up_a, heading, R)
        if s["gnss_max_acc"] > 0 and math.hypot(dv[0], dv[1]) > s["gnss_max_acc"] * dT:
            gs.rejected = True  # a jump
            return
        if gs.used and gs.time - gs.used_t <= s["gnss_timeout"]:  # aided: the gate refuses
            if s["gnss_gate"] > 0 and any(y * y > s["gnss_gate"] ** 2 * (h @ self.P @ h + R) for h, y in rows):
                gs.rejected = True
                return
        else:
            # (re)starting the aiding: the inclination was the accelerometer's alone, tilted by
            # whatever it read as gravity; P describes neither that error nor its relation to the
            # other states: the inclination is uncorrelated again, and wider where the velocities
            # can tell both its axes (heading known: the full vectors are compared) or disagree
            gated = s["gnss_gate"] > 0 and any(y * y > s["gnss_gate"] ** 2 * (h @ self.P @ h + R) for h, y in rows)
            keep = np.ones((6, 6), bool)
            keep[:2, :] = keep[:, :2] = False
            keep[0, 0] = keep[1, 1] = True
            self.P = np.where(keep, self.P, 0.0)
            if heading or gated:
                self.P = self.P + np.diag([1.0, 1.0, 0, 0, 0, 0]) * s["init_att_sigma"] ** 2
        x = np.zeros(6)
        states = (0, 1, 2, 3, 4, 5) if heading else (0, 1, 3, 4, 5)
        for h, y in rows:
            self._row(x, h, y, R, states)
        self._inject(x)
        gs.set_anchor(t, sv_t, v, var, has_up, x[:3], s["gravity"])
        gs.used, gs.used_t = True, t

    def _inject(self, x: F) -> None:
        """q ← exp(δθ) ⊗ q, b ← b + δb; the navigation-frame vectors carried through (I + [δθ×])."""
        assert self.q is not None and self.acc_lp is not None
        self.q = _qmul(_exp(x[:3]), self.q)
        self.acc_lp = self.acc_lp + np.cross(x[:3], self.acc_lp)
        if self.tilt is not None:
            self.tilt = self.tilt + np.cross(x[:3], self.tilt)
        if self.tilt_start is not None and len(self.tilt_start):
            self.tilt_start = self.tilt_start + np.cross(x[:3], self.tilt_start)
        self.b = self.b + x[3:]

    def _row(self, x: F, h: F, y: float, R: float, states: tuple[int, ...]) -> None:
        """A scalar measurement y = h x + noise (R) with a general row h; gain masked to states;
        Joseph form."""
        S = float(h @ self.P @ h) + R
        keep = np.zeros(6)
        keep[list(states)] = 1.0
        K = self.P @ h / S * keep
        x += K * (y - float(h @ x))
        A = np.eye(6) - np.outer(K, h)
        self.P = A @ self.P @ A.T + R * np.outer(K, K)


class _GnssState:
    """The clock, the specific-force integral since the anchor and its history, the anchor."""

    def __init__(self) -> None:
        self.time = 0.0
        self.last_dt = 0.0
        self.armed = self.used = self.aided = self.rejected = False
        self.used_t = 0.0
        self.sv = np.zeros(3)  # ∫ (f_n − g e_z) dt, relative to the anchor's
        self.entries: list[tuple[float, F]] = []  # (time, sv), oldest first, at most GNSS_HIST
        self.anchor: tuple[float, F, F, float, bool] | None = None  # t, sv at t, velocity, variance, has_up

    def arm(self) -> None:
        self.armed, self.sv, self.entries = True, np.zeros(3), [(self.time, np.zeros(3))]

    def record(self, fnav: F, dt: float, g: float, aided: bool, spacing: float) -> None:
        self.time += dt
        self.last_dt = dt
        self.rejected, self.aided = False, aided
        if not self.armed:
            return
        self.sv = self.sv + (fnav - np.array([0.0, 0.0, g])) * dt
        if self.time - self.entries[-1][0] >= spacing:
            self.entries = (self.entries + [(self.time, self.sv.copy())])[-GNSS_HIST:]

    def integral_at(self, t: float) -> F | None:
        """sv at t: linear between the history's entries and the current value; None before them."""
        pts = self.entries + [(self.time, self.sv)]
        if t >= self.time:
            return self.sv.copy()
        for (t0, s0), (t1, s1) in zip(reversed(pts[:-1]), reversed(pts[1:])):
            if t >= t0:
                return s0 + ((t - t0) / (t1 - t0) if t1 > t0 else 0.0) * (s1 - s0)
        return None

    def set_anchor(self, t: float, sv_t: F, v: F, var: float, has_up: bool, th: F, g: float) -> None:
        """The anchor moves to t; every integral is re-based to it and the specific force
        integrated since, F_rel = sv − sv_t + g (t_x − t) e_z, turned by the correction th."""
        def turn(tx: float, sx: F) -> F:
            rel = sx - sv_t
            return rel + np.cross(th, rel + np.array([0.0, 0.0, g * (tx - t)]))

        self.entries = [(tx, turn(tx, sx)) for tx, sx in self.entries]
        self.sv = turn(self.time, self.sv)
        self.anchor = (t, np.zeros(3), v.copy(), var, has_up)


def ahrs_reference(gyr: ArrayLike, acc: ArrayLike, mag: ArrayLike | None = None, rate: float = 100.0,
                   q0: ArrayLike | None = None, **settings: Any) -> F:
    """(N, 4) attitudes of the model filter over N samples at ``rate`` Hz."""
    g = np.asarray(gyr, float)
    a = np.asarray(acc, float)
    mm = None if mag is None else np.asarray(mag, float)
    f = ReferenceAhrs(q0=q0, **settings)
    out = np.empty((len(g), 4))
    for i in range(len(g)):
        out[i] = f.update(g[i], a[i], None if mm is None else mm[i], 1.0 / rate)
    return out
