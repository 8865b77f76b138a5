"""attitude_c.ahrs (attitude_c.ahrs_filter): the attitude filter against its NumPy model and the truth.

Differential: the C filter (double) against attitude_c.reference.ahrs (matrix
form of the same equations, written from docs/ahrs.md) on synthetic motion
and on a BROAD segment; the float build against the double build. Truth:
closed-form constant-rate motion (q(t) = q0 ⊗ exp(ω t), exact sensors), where
the filter must converge to the truth and learn a gyro bias.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import M_N as conftest_M_N
from conftest import G, angle_deg, motion

from attitude_c import broad, names
from attitude_c import reference as ref
from attitude_c.ahrs_filter import Ahrs, ahrs, default_settings
from attitude_c.errors import InvalidArgument, InvalidType, NonFiniteError
from attitude_c.reference.ahrs import ahrs_reference


@pytest.mark.parametrize("method", ["rv3-reuse", "rv1", "rv3"])
def test_c_matches_reference_synthetic(method):
    gyr, acc, mag, _ = motion(900, 100.0, (0.3, -0.2, 0.5), q0=ref.euler_to_quat([0.4, 0.2, -0.3]),
                              bias=(0.01, -0.02, 0.005), noise=0.002)
    qc = ahrs(gyr, acc, mag, rate=100.0, method=method)
    qr = ahrs_reference(gyr, acc, mag, rate=100.0, method=method)
    # both are exact evaluations of the same recursion in double; the
    # feedback keeps rounding differences from growing: 1e-12 is ~1e4 ulp
    assert np.abs(qc - qr).max() < 1e-12


def test_c_matches_reference_six_axis_and_gate():
    gyr, acc, _mag, _ = motion(600, 100.0, (0.0, 0.0, 0.8), noise=0.003)
    acc[200:260] += [6.0, 0.0, 0.0]  # a linear-acceleration burst: exercises the gate
    kw = {"acc_tau": 0.2, "acc_gate": 0.05, "acc_reject_max": 0.3, "sensor_delay": 0.003}
    qc = ahrs(gyr, acc, None, rate=100.0, **kw)
    qr = ahrs_reference(gyr, acc, None, rate=100.0, **kw)
    assert np.abs(qc - qr).max() < 1e-12  # as above


@pytest.mark.parametrize("delays", [(0.005, 0.013), (-0.02, 0.05), (0.0, -0.01)])
def test_c_matches_reference_with_sensor_delays(delays):
    """acc_delay / mag_delay: the C's cross products against the model's matrix series."""
    gyr, acc, mag, _ = motion(900, 100.0, (2.0, -1.5, 3.0), q0=ref.euler_to_quat([0.4, 0.2, -0.3]),
                              bias=(0.01, -0.02, 0.005), noise=0.002)
    kw = {"acc_delay": delays[0], "mag_delay": delays[1]}
    qc = ahrs(gyr, acc, mag, rate=100.0, **kw)
    qr = ahrs_reference(gyr, acc, mag, rate=100.0, **kw)
    assert np.abs(qc - qr).max() < 1e-12  # as above
    q0 = ahrs(gyr, acc, mag, rate=100.0)
    assert np.abs(qc - q0).max() > 1e-4  # the compensation is taken (|θ| up to 0.2 rad here)
    qf = ahrs(gyr, acc, mag, rate=100.0, precision="f32", **kw)
    assert angle_deg(qf.astype(float), qc).max() < np.degrees(1e-4)  # float: as on the BROAD segment


@pytest.mark.parametrize("tilt_tau", [0.0, 0.5])
def test_c_matches_reference_reported_inclination(tilt_tau):
    """The reported inclination's low-pass off (the state's own) and fast (0.5 s: it
    moves within the record), nine-axis, rv3-reuse."""
    gyr, acc, mag, _ = motion(900, 100.0, (0.6, -0.4, 1.0), q0=ref.euler_to_quat([0.4, 0.2, -0.3]),
                              bias=(0.01, -0.02, 0.005), noise=0.002)
    acc[300:400] += [1.5, -1.0, 0.0]  # a sustained push: the low-pass visibly moves
    qc = np.asarray(ahrs(gyr, acc, mag, rate=100.0, tilt_tau=tilt_tau))
    qr = ahrs_reference(gyr, acc, mag, rate=100.0, tilt_tau=tilt_tau)
    assert np.abs(qc - qr).max() < 1e-12  # as above


def test_c_matches_reference_rest_then_motion():
    """Rest (zero-rate update, gyr_noise_rest) then turning (gyr_noise): both process noises."""
    g0, a0, m0, _ = motion(300, 100.0, (0.0, 0.0, 0.0), bias=(0.004, -0.003, 0.002), noise=0.0005)
    g1, a1, m1, _ = motion(300, 100.0, (0.0, 0.0, 0.6), bias=(0.004, -0.003, 0.002), noise=0.0005)
    gyr, acc, mag = np.vstack([g0, g1]), np.vstack([a0, a1]), np.vstack([m0, m1])
    f = Ahrs(rate=100.0)
    flags = [f.update(gyr[i], acc[i], mag[i]) is not None and f.flags for i in range(len(gyr))]
    assert any(fl & names.C["ATT_AHRS_F_REST"] for fl in flags[:300])  # the rest path is taken
    qc = ahrs(gyr, acc, mag, rate=100.0)
    qr = ahrs_reference(gyr, acc, mag, rate=100.0)
    assert np.abs(qc - qr).max() < 1e-12  # as above


def test_c_matches_reference_on_broad_segment():
    folder = broad.default_dir()
    if folder is None:
        pytest.skip("BROAD data not found beside the checkout (../shared/data/broad)")
    t = broad.load_trial(folder / "29_disturbed_stationary_magnet_B.mat")
    sl = slice(8000, 9500)  # rest, then motion near the magnet: rest, rejection, relearn paths
    qc = ahrs(t.gyr[sl], t.acc[sl], t.mag[sl], rate=t.rate)
    qr = ahrs_reference(t.gyr[sl], t.acc[sl], t.mag[sl], rate=t.rate)
    assert np.abs(qc - qr).max() < 1e-12  # as above
    qf = ahrs(t.gyr[sl], t.acc[sl], t.mag[sl], rate=t.rate, precision="f32")
    # float: the state carries ~1e-7 relative rounding per step, damped by
    # the filter's ~1 s time constants: 1e-4 rad (0.006°) bounds it
    assert angle_deg(qf.astype(float), qc).max() < np.degrees(1e-4)


def _disturbed_start(seconds: float, n: int):
    """Turning at 0.5 rad/s about up with a z-bias, for the first ``seconds`` in a field
    with 10 µT more downward (a homogeneous other field: norm +20 %, dip +6°, as beside a
    stationary magnet at the start)."""
    gyr, acc, mag, truth = motion(n, 100.0, (0.0, 0.0, 0.5), bias=(0, 0, 0.01), noise=0.002)
    k = round(seconds * 100)
    mag[:k] += np.einsum("nji,j->ni", ref.quat_to_dcm(truth[:k]), [0.0, 0.0, -10.0])  # C^T d_n
    return gyr, acc, mag, truth


def test_c_matches_reference_magnetic_reference_paths():
    """A disturbed start longer than mag_ref_window: the young reference restarts, is
    established on the disturbed field, the clean field is rejected, then relearned
    from the candidate (mag_new_time 3 s of turning)."""
    gyr, acc, mag, _ = _disturbed_start(7.0, 1500)
    kw = {"mag_new_time": 3.0}
    f = Ahrs(rate=100.0, **kw)
    flags = np.array([f.update(gyr[i], acc[i], mag[i]) is not None and f.flags for i in range(len(gyr))])
    assert (flags & names.C["ATT_AHRS_F_MAG_DISTURBED"]).any()  # rejection path taken
    assert (flags & names.C["ATT_AHRS_F_MAG_RELEARNED"]).any()  # relearn path taken
    qc = ahrs(gyr, acc, mag, rate=100.0, **kw)
    qr = ahrs_reference(gyr, acc, mag, rate=100.0, **kw)
    assert np.abs(qc - qr).max() < 1e-12  # as above


def test_disturbed_first_second_does_not_poison_the_reference():
    """A field disturbed for the first second only: the reference (young until it holds
    mag_ref_window = 5 s of weight) restarts on the clean field, which is then never
    rejected, and ends at the clean field's norm and dip (closed form: conftest.M_N).
    The one-sample start (mag_ref_window 0, the rule before issue 28) rejects the clean
    field until the candidate has turned for mag_new_time (20 s)."""
    gyr, acc, mag, _ = _disturbed_start(1.0, 4000)
    dist = names.C["ATT_AHRS_F_MAG_DISTURBED"]
    rejected = {}
    for window in (5.0, 0.0):
        f = Ahrs(rate=100.0, mag_ref_window=window)
        flags = np.array([f.update(gyr[i], acc[i], mag[i]) is not None and f.flags for i in range(len(gyr))])
        rejected[window] = float(np.count_nonzero(flags[100:] & dist)) / 100.0  # s, after the disturbance
        if window:
            norm, dip = float(f._s.mag_ref[0]), float(f._s.mag_ref[1])
    assert rejected[5.0] == 0.0
    assert rejected[0.0] >= 19.0  # the contrast: 20 s of turning minus the first second
    mn = np.asarray(conftest_M_N)
    # the reference is the mean of ~35 s of samples: the field's noise (0.1 µT per axis) and
    # the tilt's error (< 0.1° here) move it far less than 0.1 % and 0.1°
    assert abs(norm - np.linalg.norm(mn)) < 1e-3 * np.linalg.norm(mn)
    assert abs(math.degrees(dip) - math.degrees(math.atan2(-mn[2], math.hypot(mn[0], mn[1])))) < 0.1


def test_converges_to_truth_and_learns_bias():
    bias = np.array([0.008, -0.006, 0.004])  # rad/s (0.6°/s, a poor MEMS gyro's turn-on bias)
    gyr, acc, mag, truth = motion(6000, 100.0, (0.4, 0.3, -0.5), bias=bias)
    # a poor gyro, started in motion (no rest to learn the bias at): its turn-on bias
    # prior is declared (init_bias_sigma 0.03 rad/s ≈ 1.7°/s; the default 0.01 is a
    # trimmed MEMS part's and learns this bias in motion more slowly)
    f = Ahrs(rate=100.0, init_bias_sigma=0.03)
    q = f.update(gyr, acc, mag)
    err = angle_deg(q, truth)
    # exact sensors, 60 s of constant turning: unaided, the bias would
    # drift 36°; with the default correction time constants (2.5 s
    # inclination, 10 s heading; bias learned over tens of seconds,
    # docs/ahrs.md) the error must fall below 0.3° and keep falling
    assert err[-1] < 0.3 and err[-1] < 0.5 * err[1000]
    assert np.linalg.norm(f.bias - bias) < 0.3 * np.linalg.norm(bias)


def test_rest_bias_and_six_axis():
    bias = np.array([0.01, -0.01, 0.02])
    # 60 s: at rest the tilt averages the accelerometer over acc_noise/gyr_noise_rest =
    # 12.5 s, so the start-up error (the bias integrated before rest is declared) takes
    # 5 of those time constants to fall below 0.01°
    gyr, acc, _, truth = motion(6000, 100.0, (0.0, 0.0, 0.0), q0=ref.euler_to_quat([0.0, 0.1, 0.2]),
                                bias=bias)
    f = Ahrs(rate=100.0)
    q = f.update(gyr, acc)
    assert f.flags & names.C["ATT_AHRS_F_REST"]
    assert np.abs(f.bias - bias).max() < 1e-3  # zero-rate update at rest: 1e-3 rad/s
    inc = broad.error_angles(q[-1:], truth[-1:])[2]
    assert np.degrees(inc[0]) < 0.01  # exact gravity: inclination to 0.01°


def test_rest_process_noise_closed_form():
    """At rest the attitude's process noise density is gyr_noise_rest. With the bias
    states switched off (init_bias_sigma = bias_noise = 0: P_θb stays 0), each tilt
    axis is a scalar random walk measured directly, whose covariance converges to the
    discrete Riccati fixed point: P⁻ = P⁺ + q, P⁺ = P⁻R/(P⁻ + R), q = σ_g² dt,
    R = σ_acc²/dt, so P⁻ = (q + √(q² + 4qR))/2."""
    rate, sr, sa = 50.0, 0.002, 0.025
    gyr, acc, _, _ = motion(int(300 * rate), rate, (0.0, 0.0, 0.0), q0=ref.euler_to_quat([0.0, 0.1, 0.2]))
    kw = {"init_bias_sigma": 0.0, "bias_noise": 0.0, "gyr_noise_rest": sr, "acc_noise": sa}
    f = Ahrs(rate=rate, **kw)
    f.update(gyr, acc)
    assert f.flags & names.C["ATT_AHRS_F_REST"]
    dt = 1.0 / rate
    q, R = sr**2 * dt, sa**2 / dt
    pm = (q + math.sqrt(q * q + 4 * q * R)) / 2
    pp = pm * R / (pm + R)
    # 300 s at rest is 24 of the loop's time constants σ_acc/σ_rest = 12.5 s: the
    # start-up transient has decayed by e^-24 ≈ 4e-11, below the 1e-9 asked
    assert f.sigma[0][:2] == pytest.approx([math.sqrt(pp)] * 2, rel=1e-9)
    # in motion (gyr_noise = 0.01) the same loop settles to √(σ_g σ_acc)-size: larger
    g = Ahrs(rate=rate, **{**kw, "gyr_noise_rest": 0.01})
    g.update(gyr, acc)
    assert g.sigma[0][0] > 2 * f.sigma[0][0]


def test_streaming_equals_batch():
    gyr, acc, mag, _ = motion(300, 100.0, (0.2, 0.1, 0.3), noise=0.002)
    qb = ahrs(gyr, acc, mag, rate=100.0)
    f = Ahrs(rate=100.0)
    qs = np.vstack([f.update(gyr[:100], acc[:100], mag[:100])]
                   + [f.update(gyr[i], acc[i], mag[i])[None] for i in range(100, 300)])
    assert np.array_equal(qb, qs)
    dt = np.full(300, 0.01)
    assert np.array_equal(ahrs(gyr, acc, mag, dt=dt), qb)


def _state(f: Ahrs) -> tuple:
    return tuple(f.q.tolist()) + tuple(f.bias.tolist()) + tuple(np.concatenate(f.sigma).tolist()) + (f.flags,)


def test_one_sample_fast_path_equals_the_general_path():
    """update's one-sample path (one C call on reused buffers) gives bit for bit what the
    general path gives: rows that take it ((3,) float64, dt None or a float) and rows
    that do not (a strided row, lists, a (1, 3) acc, a 0-d array dt, a big-endian row, a
    masked array with nothing masked), mixed in one stream, against the batch call."""
    gyr, acc, mag, _ = motion(240, 100.0, (0.2, -0.1, 0.3), noise=0.002)
    qb = ahrs(gyr, acc, mag, rate=100.0)
    wide = np.zeros((240, 6))
    wide[:, ::2] = gyr  # rows of wide[:, ::2] are (3,) float64 but strided
    f = Ahrs(rate=100.0)
    out = []
    for i in range(240):
        g, a, m, dt = gyr[i], acc[i], mag[i], None
        kind = i % 6
        if kind == 1:
            g, dt = wide[i, ::2], 0.01
        elif kind == 2:
            a, m = acc[i].tolist(), list(mag[i])
        elif kind == 3:
            a, dt = acc[i][None], np.array(0.01)
        elif kind == 4:
            g, m = gyr[i].astype(">f8"), np.ma.masked_array(mag[i])  # same values, general path
        out.append(f.update(g, a, m, dt))
    assert np.array_equal(np.vstack(out), qb)
    assert all(q.shape == (4,) and q.dtype == np.float64 for q in out)
    assert out[5] is not out[6] and not np.shares_memory(out[5], out[11])  # fresh arrays


@pytest.mark.parametrize("bad", ["gyr-nan", "acc-inf", "mag-nan", "dt-zero", "dt-nan", "dt-negative"])
def test_one_sample_errors_name_the_argument_and_keep_the_state(bad: str):
    gyr, acc, mag, _ = motion(60, 100.0, (0.2, -0.1, 0.3), noise=0.002)
    f, ref_ = Ahrs(rate=100.0), Ahrs(rate=100.0)
    f.update(gyr[:50], acc[:50], mag[:50])
    ref_.update(gyr[:50], acc[:50], mag[:50])
    g, a, m, dt = gyr[50].copy(), acc[50].copy(), mag[50].copy(), None
    if bad == "gyr-nan":
        g[1] = np.nan
    elif bad == "acc-inf":
        a[2] = np.inf
    elif bad == "mag-nan":
        m[0] = np.nan
    else:
        dt = {"dt-zero": 0.0, "dt-nan": math.nan, "dt-negative": -0.01}[bad]
    name = bad.split("-")[0]
    with pytest.raises(InvalidArgument, match=rf"^{name}: sample 0"):
        f.update(g, a, m, dt)
    assert _state(f) == _state(ref_)
    assert np.array_equal(f.update(gyr[50], acc[50], mag[50]), ref_.update(gyr[50], acc[50], mag[50]))


def test_overrange_flag():
    gyr, acc, mag, _ = motion(50, 100.0, (0.0, 0.0, 3.0))
    f = Ahrs(rate=100.0, gyro_range=2.0)
    f.update(gyr, acc, mag)
    assert f.flags & names.C["ATT_AHRS_F_OVERRANGE"]


def test_errors():
    gyr, acc, mag, _ = motion(20, 100.0, (0.1, 0, 0))
    with pytest.raises(InvalidArgument, match="ATT_E_AHRS_UNITS"):
        ahrs(gyr, acc / G, mag, rate=100.0)  # accelerometer in g
    bad = gyr.copy()
    bad[5, 1] = np.nan
    with pytest.raises(NonFiniteError) as e:
        ahrs(bad, acc, mag, rate=100.0)
    assert e.value.index == 5
    with pytest.raises(InvalidArgument, match="dt"):
        ahrs(gyr, acc, mag, dt=np.r_[np.full(10, 0.01), 0.0, np.full(9, 0.01)])
    with pytest.raises(InvalidArgument, match="unknown filter setting"):
        ahrs(gyr, acc, rate=100.0, acc_tauu=1.0)
    with pytest.raises(InvalidArgument, match="domain"):
        ahrs(gyr, acc, rate=100.0, acc_noise=-1.0)
    with pytest.raises(InvalidArgument, match="domain"):
        ahrs(gyr, acc, rate=100.0, gyr_noise_rest=0.0)
    with pytest.raises(InvalidArgument, match=r"mag_delay=0.06 outside its domain .*0.05 s"):
        ahrs(gyr, acc, mag, rate=100.0, mag_delay=0.06)  # a lag is ≤ 50 ms (ahrs.h)
    with pytest.raises(InvalidArgument, match="acc_delay"):
        ahrs(gyr, acc, mag, rate=100.0, acc_delay=-0.06)
    with pytest.raises(InvalidArgument, match="rk4"):
        Ahrs(rate=100.0, method="rk4")
    with pytest.raises(InvalidType):
        Ahrs(rate=100.0, acc_tau="2")
    with pytest.raises(InvalidArgument, match="shape"):
        ahrs(gyr[:, :2], acc, rate=100.0)
    with pytest.raises(InvalidArgument, match="rate"):
        ahrs(gyr, acc)


def test_defaults_documented():
    d = default_settings()
    assert d["method"] == "rv3-reuse"
    assert math.isclose(d["gravity"], 9.81)
    from attitude_c.reference import ahrs as mref
    assert d == pytest.approx(mref._DEFAULTS)  # the model uses the library's defaults


def test_the_issue_names_are_the_package_api() -> None:
    """`attitude_c.Ahrs` (streaming) and `attitude_c.ahrs(...)` (batch) as the docs name them."""
    import attitude_c
    from attitude_c import ahrs_filter

    assert attitude_c.Ahrs is ahrs_filter.Ahrs and attitude_c.ahrs is ahrs_filter.ahrs
    assert "Ahrs" in attitude_c.__all__ and "ahrs" in attitude_c.__all__


def test_streaming_bench_smoke():
    """bench/broad.py's streaming table on 200 synthetic samples (the full run on BROAD:
    invoke bench --only broad): each of the three filters and the bare loop runs on the
    same rows; the times are the benchmark's business, not the test's."""
    from types import SimpleNamespace

    from bench.broad import streaming

    gyr, acc, mag, _ = motion(200, 100.0, (0.2, -0.1, 0.3), noise=0.002)
    us = streaming([SimpleNamespace(gyr=gyr, acc=acc, mag=mag, rate=100.0)], n=200, rounds=1)
    assert len(us) == 4 and all(len(v) == 1 and np.isfinite(v[0]) and v[0] >= 0 for v in us.values())


@pytest.mark.parametrize("precision", ["f64", "f32"])
def test_setting_field_table_is_every_real_field_in_order(precision: str) -> None:
    """att_ahrs_setting_field walks the struct's real fields in order with their offsets (what
    attitude-rx reads its settings by), the count in the header, NULL past the last; truth:
    the struct as the compiler laid it out (CFFI's view of the header)."""
    from attitude_c._lib import ffi_lib

    ffi, lib = ffi_lib(precision)
    real = [(n, f.offset) for n, f in ffi.typeof("att_ahrs_settings").fields if f.type.cname in ("double", "float")]
    off = ffi.new("size_t *")
    got = [(ffi.string(lib.att_ahrs_setting_field(i, off)).decode(), off[0]) for i in range(lib.ATT_AHRS_REAL_SETTINGS)]
    assert got == real
    assert lib.att_ahrs_setting_field(lib.ATT_AHRS_REAL_SETTINGS, off) == ffi.NULL
