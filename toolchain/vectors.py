"""Test vectors for the C runner (csrc/vectors/run_vectors.c), from the NumPy reference.

``generate(seed)`` builds every case: inputs (seeded random plus the
special cases: identity, 180° rotations, tiny and large rotation vectors,
θ = ±90°, non-finite inputs) and the expected outputs of
``attitude_c.reference`` (float64). ``write(cases, path)`` writes the
runner's input file; ``parse(text)`` reads the runner's output;
``compare(cases, results, precision)`` returns the mismatches.

The same file runs on every target (host, ARMv4T bare metal under
``qemu-arm -cpu ti925t``, ARM Linux under ``qemu-arm``); pytest compares
each target's output with the reference (tests/test_vectors.py).

Inputs are rounded to float32 so that the float build of the library
sees exactly the values the reference used (its errors are then its own
arithmetic only, which the float tolerances below are derived from).

Command line (to run the vectors on a real board)::

    python -m toolchain.vectors --out vectors.txt
    ./run_vectors vectors.txt > results.txt
    python -m toolchain.vectors --check results.txt [--precision f32]
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from attitude_c import core

ROOT = Path(__file__).resolve().parents[1]
RUNNER_SRC = ROOT / "csrc" / "vectors" / "run_vectors.c"

#: float32 unit roundoff (2^-24): the size of one rounding in the float build.
EPS32 = 2.0 ** -24
#: float64 unit roundoff (2^-53).
EPS64 = 2.0 ** -53

#: The methods whose increments the vectors integrate (every one but rk4: the library's list).
INCREMENT_METHODS = core.INCREMENT_METHODS


@dataclass
class Case:
    id: str
    func: str
    inputs: np.ndarray              # (N, arity) float64, float32-representable
    params: list[str] = field(default_factory=list)
    expected: np.ndarray | None = None  # (M, out_arity) float64
    status_ok: bool = True          # False: the C call must fail
    err_index: int = -1             # expected failing record (when not status_ok)
    kind: str = "plain"             # comparison: plain | quat (up to sign) | angle (mod 2π) | euler
    ops: int = 20                   # float roundings behind one output (tolerance scale)
    scale: float = 1.0              # magnitude of the outputs
    tol: dict[str, float] | None = None  # explicit tolerance per precision (iterative solvers)


def _ref() -> Any:
    from attitude_c import reference

    return reference


def _f32(x: np.ndarray) -> np.ndarray:
    return np.asarray(x, dtype=np.float32).astype(np.float64)


def _unit_quats(rng: np.random.Generator, n: int) -> np.ndarray:
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return _f32(q)


def _special_quats() -> np.ndarray:
    s = math.sqrt(0.5)
    return _f32(np.array([
        [1, 0, 0, 0],          # identity
        [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1],   # 180° about x, y, z
        [0, s, s, 0],          # 180° about a diagonal
        [s, s, 0, 0],          # +90° about x: pitch = +90° (gimbal lock)
        [s, -s, 0, 0],         # pitch = -90°
        [s, 0, 0, s],          # 90° yaw
        [1, 1e-7, -1e-7, 1e-7],  # tiny rotation
    ], dtype=np.float64))


def _euler_random(rng: np.random.Generator, n: int, pitch_margin: float) -> np.ndarray:
    """[ψ, θ, γ] away from the ±180° wrap of ψ, γ and from gimbal lock by pitch_margin."""
    e = np.column_stack([
        rng.uniform(-3.1, 3.1, n),
        rng.uniform(-math.pi / 2 + pitch_margin, math.pi / 2 - pitch_margin, n),
        rng.uniform(-3.1, 3.1, n),
    ])
    return _f32(e)


def generate(seed: int = 20100601, n: int = 64) -> list[Case]:
    """Every vector case, with the reference's expected outputs."""
    ref = _ref()
    rng = np.random.default_rng(seed)
    cases: list[Case] = []

    def add(func: str, inputs: np.ndarray, expected: Any, **kw: Any) -> None:
        cases.append(Case(f"{func}.{len(cases)}", func, np.asarray(inputs, dtype=np.float64),
                          expected=None if expected is None else
                          np.asarray(expected, dtype=np.float64).reshape(len(inputs), -1), **kw))

    q = np.vstack([_special_quats(), _unit_quats(rng, n)])
    q_scaled = _f32(q * rng.uniform(0.5, 2.0, size=(len(q), 1)))  # not unit
    a, b = _unit_quats(rng, n), _unit_quats(rng, n)
    add("quat_mul", np.hstack([a, b]), ref.quat_multiply(a, b), ops=8)
    add("quat_conj", q, ref.quat_conj(q), ops=1)
    add("quat_normalize", q_scaled, ref.quat_normalize(q_scaled), ops=12)
    phi = np.vstack([
        np.zeros((1, 3)),
        _f32(rng.normal(size=(n, 3)) * 1e-6),   # tiny: series branch
        _f32(rng.normal(size=(n, 3)) * 0.05),   # near the series/trig switch (φ = 0.2)
        _f32(rng.normal(size=(n, 3)) * 1.5),    # large
        _f32(np.array([[math.pi, 0, 0], [0, 0, -3.1]])),
    ])
    add("rotvec_to_quat", phi, ref.rotvec_to_quat(phi), kind="quat", ops=20)
    # quat -> rotvec: away from 180° (the sign flip there is a discontinuity)
    qr = q[np.abs(q[:, 0]) > 0.05]
    add("quat_to_rotvec", qr, ref.quat_to_rotvec(qr), ops=40, scale=math.pi)
    add("quat_to_dcm", q_scaled, ref.quat_to_dcm(q_scaled).reshape(-1, 9), ops=20)
    C = ref.quat_to_dcm(q).reshape(-1, 9)
    Cf = _f32(C)
    add("dcm_to_quat", Cf, ref.dcm_to_quat(Cf.reshape(-1, 3, 3)), kind="quat", ops=40)
    e = _euler_random(rng, n, pitch_margin=0.05)
    Ce = _f32(ref.euler_to_dcm(e).reshape(-1, 9))
    add("dcm_to_euler", Ce, ref.dcm_to_euler(Ce.reshape(-1, 3, 3)), kind="euler", ops=40,
        scale=math.pi)
    add("euler_to_dcm", e, ref.euler_to_dcm(e).reshape(-1, 9), ops=30)
    qe = _f32(ref.euler_to_quat(e))
    add("quat_to_euler", qe, ref.quat_to_euler(qe), kind="euler", ops=40, scale=math.pi)
    add("euler_to_quat", e, ref.euler_to_quat(e), kind="quat", ops=30)
    add("quat_heading", qe, np.asarray(ref.heading(qe)).reshape(-1, 1), kind="angle", ops=40,
        scale=2 * math.pi)
    add("dcm_heading", Ce, np.asarray(ref.heading(Ce.reshape(-1, 3, 3))).reshape(-1, 1),
        kind="angle", ops=40, scale=2 * math.pi)
    # gimbal lock: exact θ = ±90° gives a defined answer (f64 only compares these exactly)
    add("quat_to_euler", q[5:7], ref.quat_to_euler(q[5:7]), kind="euler", ops=40, scale=math.pi)

    # bad input: NaN / Inf in the 3rd record, zero quaternion
    bad = q[:5].copy()
    bad[2, 1] = np.nan
    add("quat_to_dcm", bad, None, status_ok=False, err_index=2)
    bad2 = phi[:5].copy()
    bad2[3, 0] = np.inf
    add("rotvec_to_quat", bad2, None, status_ok=False, err_index=3)
    zero = np.vstack([q[:1], np.zeros((1, 4))])
    add("quat_normalize", zero, None, status_ok=False, err_index=1)

    # integrator: every method, random ~1 rad/s motion at 100 Hz, plus a constant rate
    for m in INCREMENT_METHODS:
        k = 150
        w = 1.0 + 0.5 * np.sin(np.arange(k)[:, None] * 0.05 + np.array([0.0, 1.0, 2.0]))
        dth = _f32(w * 0.01 * np.array([1.0, -0.7, 0.4]))
        q0 = _unit_quats(rng, 1)[0]
        out = ref.integrate(dth, method=m, q0=q0)
        cases.append(Case(f"integ.{m}.{len(cases)}", "integ", dth, params=[m, *(repr(float(v)) for v in q0)],
                          expected=np.asarray(out, dtype=np.float64), kind="quat", ops=12 * len(out)))
    dth = _f32(np.tile([[0.002, -0.001, 0.003]], (30, 1)))
    dth[17, 2] = np.nan
    cases.append(Case(f"integ.nan.{len(cases)}", "integ", dth, params=["rv3", "1", "0", "0", "0"],
                      status_ok=False, err_index=17))
    # rk4 from rates: first sample = start, then alternating midpoint / end
    k = 121
    t = np.arange(k) * 0.005
    omega = _f32(np.column_stack([np.sin(2 * t), 0.5 * np.cos(3 * t), 0.3 + 0 * t]))
    h = 0.01  # step of the C call = 2 sample spacings (start, midpoint, end)
    out = ref.integrate_rates(omega, h / 2, method="rk4")
    cases.append(Case(f"rk4.{len(cases)}", "rk4", omega, params=[repr(h), "1", "0", "0", "0"],
                      expected=np.asarray(out, dtype=np.float64), kind="quat", ops=40 * len(out)))
    # link checksum
    blk = rng.integers(0, 256, size=(1, 64)).astype(np.float64)
    cases.append(Case(f"link_checksum.{len(cases)}", "link_checksum", blk.reshape(-1, 1).T,
                      expected=np.array([[float(int(blk.sum()) % 256)]]), ops=0))
    for c in link_cases(rng):
        c.id = f"{c.id}.{len(cases)}"
        cases.append(c)
    for c in denoise_cases(rng):
        c.id = f"{c.id}.{len(cases)}"
        cases.append(c)
    for c in sensor_cases(rng):
        c.id = f"{c.id}.{len(cases)}"
        cases.append(c)
    for c in aiding_cases(rng):
        c.id = f"{c.id}.{len(cases)}"
        cases.append(c)
    return cases


def aiding_cases(rng: np.random.Generator, n: int = 48) -> list[Case]:
    """The aiding solvers (attitude/aiding.h) against attitude_c.reference.aiding:
    alignment (nine- and six-axis), TRIAD and Gauss–Newton (both methods) on noisy
    body vectors of random attitudes (|pitch| ≤ 80°: the float tolerances below
    assume atan2 and the cross products away from the vertical), the static window,
    the three ellipsoid fits, the 2-D min/max method and the apply function, plus a
    parallel pair, a zero field and a non-finite sample (the error names the record)."""
    from attitude_c import reference as ref
    from attitude_c.reference import aiding as ra

    out: list[Case] = []
    decl = float(_f32(np.array([0.25]))[0])
    e = _f32(np.column_stack([rng.uniform(-3.1, 3.1, n), rng.uniform(-1.4, 1.4, n), rng.uniform(-3.1, 3.1, n)]))
    C = ref.euler_to_dcm(e)
    f = _f32(np.einsum("nji,j->ni", C, [0.0, 0.0, 9.81]) + rng.normal(scale=0.05, size=(n, 3)))
    m = _f32(np.einsum("nji,j->ni", C, ra.field_nav(48.0, 1.1, 0.25)) + rng.normal(scale=0.4, size=(n, 3)))
    # align/TRIAD: unit vectors, cross products, atan2 and the Euler → quaternion (or
    # Shepperd) chain: ~60 roundings of unit-size values
    out.append(Case("align", "align", np.hstack([f, m]), params=[repr(decl), "0"],
                    expected=ra.align(f, m, decl), kind="quat", ops=60))
    out.append(Case("align6", "align", f, params=[repr(decl), "1"], expected=ra.align(f, None), kind="quat", ops=60))
    out.append(Case("triad", "triad", np.hstack([f, m]), params=[repr(decl)], expected=ra.triad(f, m, decl),
                    kind="quat", ops=60))
    q0 = _f32(ref.quat_multiply(ra.align(f, m, decl), ref.rotvec_to_quat(rng.normal(scale=0.1, size=(n, 3)))))
    # Gauss–Newton stops when |r| ≤ tol_residual (1e-13 double, 2e-6 float): the
    # attitude error is of that order (times ~3 for the conditioning of the four
    # equations at |pitch| ≤ 80°), above the rounding bound of the direct solvers
    qg, conv = ra.gauss_newton(f, m, q0, decl)
    assert conv.all()
    for meth in (0, 1):
        out.append(Case(f"gn{meth}", "gn", np.hstack([f, m, q0]), params=[repr(decl), str(meth), "20" if meth == 0 else "200"], expected=qg,
                        kind="quat", tol={"f64": 1e-11, "f32": 2e-5}))
    bad = np.hstack([f[:6], m[:6]])
    bad[2, 3:] = -3 * bad[2, :3]  # field parallel to the specific force
    out.append(Case("triad.parallel", "triad", bad, params=["0"], status_ok=False, err_index=2))
    bad = np.hstack([f[:6], m[:6]])
    bad[4, 3:] = 0.0
    out.append(Case("align.zero_m", "align", bad, params=["0", "0"], status_ok=False, err_index=4))
    bad = np.hstack([f[:6], m[:6], q0[:6]])
    bad[1, 0] = np.nan
    out.append(Case("gn.nan", "gn", bad, params=["0", "0", "20"], status_ok=False, err_index=1))
    # static window: 200 noisy samples of one attitude; the mean's attitude
    k = 200
    ew = e[:1]
    Cw = ref.euler_to_dcm(ew)[0]
    acc = _f32(Cw.T @ [0.0, 0.0, 9.81] + rng.normal(scale=0.05, size=(k, 3)))
    mag = _f32(Cw.T @ ra.field_nav(48.0, 1.1, 0.25) + rng.normal(scale=0.4, size=(k, 3)))
    gyr = _f32(rng.normal(scale=0.01, size=(k, 3)))
    # the window's means (Welford): one rounding per sample and component, ~k·ε relative
    out.append(Case("align_window", "align_window", np.hstack([gyr, acc, mag]), params=[repr(decl)],
                    expected=ra.align(acc.mean(axis=0), mag.mean(axis=0), decl)[None, :], kind="quat",
                    ops=60 + 2 * k))
    mov = np.hstack([gyr, acc, mag])
    mov[:, 3] += _f32(np.linspace(-3, 3, k))  # the specific force swings: a moving start
    out.append(Case("align_window.moving", "align_window", mov, params=[repr(decl)], status_ok=False, err_index=0))
    # magnetometer fits: the acceptance case (cond 2, offset 1.5 B, 1 % noise) per model
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    A = Q @ np.diag([1.0, 2.0, 1.4]) @ Q.T
    hb = np.array([50.0, -45.0, 30.0])
    u = rng.normal(size=(300, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    raw = _f32((48.0 * u) @ A.T + hb + rng.normal(scale=0.48, size=(300, 3)))
    for name, code in (("offset", 0), ("diagonal", 1), ("full", 2)):
        r = ra.magcal_fit(raw, name)
        exp = np.concatenate([r["h"], r["S"].ravel(), [r["field"]]])[None, :]
        # absolute, on h and field (~50 units) and S (~1): the 1e-9 in double
        # (observed 3e-13); in float the moments' rounding (~300 terms of 2^-24) times
        # the normal equations' condition (~1e3 here) gives ~1e-6 relative, observed
        # 6e-5 absolute (1e-6 of the offsets): 1e-3 absolute is ~20e-6 relative
        out.append(Case(f"magcal.{name}", "magcal", raw, params=[str(code)], expected=exp,
                        tol={"f64": 1e-9, "f32": 1e-3}))
    out.append(Case("magcal.nan", "magcal", np.vstack([raw[:30], [[np.nan, 0, 0]]]), params=["2"],
                    status_ok=False, err_index=30))
    out.append(Case("magcal.span", "magcal", raw[:, :2] @ np.eye(2, 3), params=["2"], status_ok=False, err_index=0))
    t = np.linspace(0, 2 * np.pi, 90, endpoint=False)
    turn = _f32(np.column_stack([12 + 26 * np.cos(t), -7 + 20 * np.sin(t), np.full_like(t, -40.0)])
                + rng.normal(scale=0.2, size=(90, 3)))
    r2 = ra.magcal_minmax_2d(turn)
    out.append(Case("magcal2d", "magcal2d", turn, expected=np.concatenate([r2["h"], r2["S"].ravel(),
                                                                           [r2["field"]]])[None, :],
                    ops=10, scale=40.0))
    cal = ra.magcal_fit(raw, "full")
    h32, S32 = _f32(cal["h"]), _f32(cal["S"])
    out.append(Case("magcal_apply", "magcal_apply", raw[:40], params=[repr(float(v)) for v in (*h32, *S32.ravel())],
                    expected=ra.magcal_apply(raw[:40], h32, S32), ops=8, scale=150.0))
    return out


def sensor_cases(rng: np.random.Generator) -> list[Case]:
    """Sensor words to increments (att_sensor_increments) against reference.sensor_values:
    plain codes and sums of 16 and of 3 conversions, permuted and signed axes, a correction
    matrix and bias (att_sensor_set_correction; the others: identity and zero), and a word
    above its limit (the error names the sample, nothing is written)."""
    ref = _ref()
    out: list[Case] = []
    for case, (n_conv, period) in enumerate(((1, 0.02), (16, 0.08), (3, 0.005), (1, 0.01))):
        corrected = case == 3
        mat = _f32(np.eye(3) + rng.uniform(-0.1, 0.1, size=(3, 3))) if corrected else np.eye(3)
        m = 40
        words = rng.integers(0, n_conv * 4095 + 1, size=(m, 3)).astype(np.float64)
        words[0] = 0
        words[1] = n_conv * 4095
        zero = _f32(rng.uniform(1800, 2300, size=3))
        scale = _f32(rng.uniform(2e-4, 2e-3, size=3) * rng.choice([-1.0, 1.0], size=3))
        axes = rng.permutation(3)
        signs = rng.choice([-1, 1], size=3)
        per = float(_f32(np.array([period]))[0])
        bias = _f32(rng.uniform(-0.5, 0.5, size=3) * float(np.max(np.abs(scale))) * 4096) if corrected \
            else np.zeros(3)
        params = [str(n_conv), repr(per), *(repr(float(v)) for v in (*zero, *scale)),
                  *(str(int(v)) for v in (*axes, *signs)), *(repr(float(v)) for v in (*mat.ravel(), *bias))]
        exp = ref.sensor_values(words, zero, scale, n_conv, axes, signs, mat, bias) * per
        # the terms before the subtraction are ~4096 codes × |scale| × period: the roundings'
        # size (the difference itself may be much smaller); the correction: 6 more roundings of
        # terms up to a row of |M| times (|value| + |b|)
        big = (4096 * float(np.max(np.abs(scale))) + float(np.max(np.abs(bias)))) * per \
            * float(np.abs(mat).sum(axis=1).max())
        name = f"sensor.corrected.n{n_conv}" if corrected else f"sensor.n{n_conv}"
        out.append(Case(name, "sensor", words, params=params, expected=exp, ops=14 if corrected else 8, scale=big))
        bad = words.copy()
        bad[7, 2] = n_conv * 4095 + 1
        if not corrected:
            out.append(Case(f"sensor.bad.n{n_conv}", "sensor", bad, params=params, status_ok=False, err_index=7))
    return out


def _wden_ops(wavelet: str, levels: int, block: int | None = None) -> int:
    """Roundings (in units of the output scale) behind one denoiser output.

    One transform level sums F products per coefficient, and the magnitude
    bound grows by ‖h‖₁ per level: L·F·‖h‖₁^L for a transform (the same
    bound as tests/test_denoise.py). A stream sample adds the inverse, the
    line fit and λ's error spread through the inverse (√(2 ln N)·√N) and
    the segment constant (sums of ≤ N terms)."""
    from attitude_c.denoise import reference as wref

    f = 2 * wref.VANISHING_MOMENTS[wavelet]
    l1 = float(np.abs(wref.filter_bank(wavelet)[0]).sum())
    ops = levels * f * l1 ** levels
    if block is not None:
        ops = 2 * ops * (1 + math.sqrt(2 * math.log(block)) * math.sqrt(block)) + block
    return math.ceil(ops)


def denoise_cases(rng: np.random.Generator) -> list[Case]:
    """The wavelet denoiser: the periodized transform both ways (every
    wavelet, a filter longer than the coarsest level included) and whole
    streams through push_n and flush, against attitude_c.denoise.reference.
    Streams use soft thresholding: with hard thresholding a float32
    rounding may move a coefficient across λ (tests/test_denoise.py
    covers hard thresholding in both builds on the host)."""
    from attitude_c.denoise import reference as wref

    out: list[Case] = []
    for w in ("haar", "db2", "db4"):
        for n, lv in ((64, 3), (16, 4)):
            x = _f32(rng.normal(size=(n, 1)) * 2.0 + 0.5)
            c = np.concatenate(wref.wavedec(x[:, 0], w, lv))
            scale = float(np.max(np.abs(x)))
            out.append(Case(f"wden_dwt.{w}", "wden_dwt", x, params=[w, str(lv)], expected=c[:, None],
                            ops=_wden_ops(w, lv), scale=scale))
            cf = _f32(c[:, None])
            back = wref.waverec([cf[: n >> lv, 0]] + [cf[(n >> k) // 2: n >> k, 0] for k in range(lv - 1, -1, -1)], w)
            out.append(Case(f"wden_idwt.{w}", "wden_idwt", cf, params=[w, str(lv)], expected=back[:, None],
                            ops=_wden_ops(w, lv), scale=float(np.max(np.abs(cf)))))
    t = np.arange(700) * 0.005
    sig = 0.3 * np.sin(2 * np.pi * 0.5 * t) + 0.02 * t
    for w, lv, block, es, ee, det in (("db4", 3, 64, 24, 8, 1), ("haar", 2, 32, 0, 0, 1),
                                      ("db2", 4, 128, 40, 30, 0)):
        x = _f32((sig + 0.01 * rng.normal(size=len(t)))[:, None])
        y = wref.denoise(x[:, 0], w, lv, block, es, ee, "soft", bool(det))
        out.append(Case(f"wden_stream.{w}", "wden_stream", x,
                        params=[w, "soft", str(lv), str(block), str(es), str(ee), str(det)], expected=y[:, None],
                        ops=_wden_ops(w, lv, block), scale=float(np.max(np.abs(x)))))
    bad = _f32(rng.normal(size=(100, 1)))
    bad[77, 0] = np.nan
    out.append(Case("wden_stream.nan", "wden_stream", bad, params=["db4", "soft", "3", "64", "24", "8", "1"],
                    status_ok=False, err_index=77))
    return out


def _link_transcript(machine: Any, events: np.ndarray, block: bytes | None) -> np.ndarray:
    """Rows (event, kind, value) as run_vectors.c prints them, from the Python end."""
    from attitude_c.link import Result

    rows: list[tuple[int, int, int]] = []
    for i, (byte, tick) in enumerate(events.astype(int)):
        tick &= 0xFFFF
        if byte == -2:
            machine.start(block, tick)
            rows.append((i, 0, 0))
        elif byte >= 0:
            rows.append((i, 0, int(machine.sink(int(byte), tick))))
        for _ in range(2 * 64 + 8):
            res, out = machine.poll(tick)
            rows.append((i, 1, int(res)))
            if res == Result.SEND:
                rows.append((i, 2, int(out)))
            if res in (Result.NONE, Result.IDLE):
                break
    st = machine.stats
    names = (("blocks_sent", "blocks_accepted", "naks", "timeouts", "gave_up", "bytes_discarded")
             if block is not None else
             ("syns", "blocks_accepted", "naks", "timeouts", "resyncs", "bytes_discarded"))
    rows += [(len(events), 3, int(getattr(st, k))) for k in names]
    return np.array(rows, dtype=np.float64)


def link_cases(rng: np.random.Generator) -> list[Case]:
    """Byte-level transcripts of receiver B and sender A; expected from the Python
    ends of attitude_c.link (written from the protocol spec, not from the C)."""
    from attitude_c.link import Receiver, Sender

    out: list[Case] = []
    # Receiver B: good blocks, bad checksum, garbage, 0xAA inside data, a gap
    # that drops a partial block, random bytes; ticks wrap through 65535.
    n_blk, gap = 6, 20
    ev: list[tuple[int, int]] = []
    tick = 65400

    def put(bs: Sequence[int], step: int = 1) -> None:
        nonlocal tick
        for b in bs:
            ev.append((b, tick))
            tick += step

    for k in range(12):
        data = [int(x) for x in rng.integers(0, 256, n_blk)]
        if k == 3:
            data[2] = 0xAA
        put([0xAA, *data, (sum(data) + (1 if k == 5 else 0)) % 256])
        if k == 7:
            put([0x13, 0x37])            # garbage, then the next handshake
        if k == 9:
            put([0xAA, 1, 2])            # truncated block ...
            ev.append((-1, tick + gap + 5))  # ... a poll after the gap drops it
            tick += gap + 10
        if k == 10:
            put([0xAA, 9])
            tick += gap + 3              # next byte arrives after the gap
    put([int(x) for x in rng.integers(0, 256, 60)], step=3)
    events = np.array(ev, dtype=np.float64)
    out.append(Case(f"link_rx.{len(out)}", "link_rx", events, params=[str(n_blk), str(gap)],
                    expected=_link_transcript(Receiver(n_blk, gap), events, None), ops=0))
    # Sender A: normal exchange, NAK + resend, lost 0xBB (timeout), lost answer,
    # garbage, give up after max attempts; ticks wrap.
    blk = bytes(int(x) for x in rng.integers(0, 256, 4))
    syn_to, ans_to, attempts = 50, 40, 3
    ev = []
    tick = 65500

    def at(b: int, dt: int = 1) -> None:
        nonlocal tick
        tick += dt
        ev.append((b, tick))

    at(-2); at(0xBB); at(0x00)                    # accepted first time
    at(-2); at(0x42); at(0xBB); at(0xFF); at(0xBB); at(0x00)  # garbage, NAK, resend
    at(-2); at(-1, syn_to + 1); at(0xBB); at(-1, ans_to + 1); at(0xBB); at(0x00)  # timeouts
    at(-2); at(-1, syn_to + 1); at(-1, syn_to + 1); at(-1, syn_to + 1); at(-1, 5)  # gives up
    at(0x00); at(-2); at(0xBB, syn_to + 5); at(-1)                  # late 0xBB
    events = np.array(ev, dtype=np.float64)
    out.append(Case(f"link_tx.{len(out)}", "link_tx", events,
                    params=[str(len(blk)), str(syn_to), str(ans_to), str(attempts), *map(str, blk)],
                    expected=_link_transcript(Sender(len(blk), syn_to, ans_to, attempts), events, blk),
                    ops=0))
    return out


def write(cases: Sequence[Case], path: str | Path) -> Path:
    """Write the runner's input file."""
    path = Path(path)
    lines = ["# libattitude test vectors (toolchain/vectors.py); inputs only, expected values stay in Python"]
    for c in cases:
        n = len(c.inputs) if c.func != "link_checksum" else c.inputs.shape[1]
        lines.append(f"case {c.id} {c.func} {n} {' '.join(c.params)}".rstrip())
        for row in c.inputs:
            lines.append(" ".join(repr(float(v)) if np.isfinite(v) else ("nan" if np.isnan(v) else
                                  ("inf" if v > 0 else "-inf")) for v in row))
    path.write_text("\n".join(lines) + "\n")
    return path


@dataclass
class Result:
    status: int
    err_index: int
    values: np.ndarray


def parse(text: str) -> tuple[dict[str, Result], str]:
    """Runner output -> ({case id: Result}, summary line)."""
    res: dict[str, Result] = {}
    lines = text.strip().splitlines()
    i = 0
    summary = ""
    while i < len(lines):
        ln = lines[i]
        if ln.startswith("= "):
            _, cid, st, err, nout = ln.split()
            rows = [list(map(float, lines[i + 1 + j].split())) for j in range(int(nout))]
            res[cid] = Result(int(st), int(err), np.array(rows, dtype=np.float64))
            i += 1 + int(nout)
        else:
            if ln.startswith("vectors:"):
                summary = ln
            i += 1
    return res, summary


def tolerance(case: Case, precision: str) -> float:
    """Absolute tolerance for one output of ``case``.

    f64: the reference and the C code use different formulas, each good to
    a few ulps per rounding; ``ops`` roundings of size ≤ 2^-53 relative,
    times the output magnitude, times 4 for the two implementations and
    the condition of the function. This is ~1e-12 or below for the
    single-call functions (the integrator issue's differential bound).
    f32: the C code rounds each of its ``ops`` operations to float32
    (2^-24 relative, worst case linear accumulation), the reference is
    exact in comparison; inputs are float32-representable so they add no
    error. Outputs are printed with 9 significant digits (round-trip for
    float32), which is covered by the same bound.
    """
    if case.tol is not None:
        return case.tol[precision]
    eps = EPS64 if precision == "f64" else EPS32
    return 4.0 * max(case.ops, 1) * eps * case.scale


def _wrap(d: np.ndarray) -> np.ndarray:
    return (d + math.pi) % (2 * math.pi) - math.pi


def compare(cases: Sequence[Case], results: dict[str, Result], precision: str) -> list[str]:
    """Mismatches between the runner's results and the reference (empty = all good)."""
    bad: list[str] = []
    for c in cases:
        r = results.get(c.id)
        if r is None:
            bad.append(f"{c.id}: no result")
            continue
        if not c.status_ok:
            if r.status >= 0 or r.err_index != c.err_index:
                bad.append(f"{c.id}: expected an error at record {c.err_index}, got status {r.status} "
                           f"at {r.err_index}")
            continue
        if r.status != 0:
            bad.append(f"{c.id}: status {r.status} at record {r.err_index}")
            continue
        assert c.expected is not None
        exp = c.expected
        if r.values.shape != exp.shape:
            bad.append(f"{c.id}: shape {r.values.shape} != expected {exp.shape}")
            continue
        if c.kind == "quat":  # q and -q are the same rotation
            sign = np.where(np.sum(r.values * exp, axis=1, keepdims=True) < 0, -1.0, 1.0)
            d = np.abs(r.values * sign - exp)
        elif c.kind in ("angle", "euler"):
            d = np.abs(_wrap(r.values - exp))
        else:
            d = np.abs(r.values - exp)
        tol = tolerance(c, precision)
        if c.kind == "euler" and precision == "f32":
            # near gimbal lock yaw and roll are ill-conditioned: an error δ in
            # the matrix moves them by δ / cos θ (θ kept ≤ 90° - 0.05 rad here)
            tol *= 1.0 / math.sin(0.05)
        worst = float(np.max(d)) if d.size else 0.0
        if not worst <= tol:
            idx = np.unravel_index(int(np.argmax(d)), d.shape)
            bad.append(f"{c.id}: |C - reference| = {worst:.3g} > {tol:.3g} at {idx}: "
                       f"{r.values[idx[0]]} vs {exp[idx[0]]}")
    return bad


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m toolchain.vectors", description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="write the runner's input file here")
    ap.add_argument("--check", help="compare a runner output file with the reference")
    ap.add_argument("--precision", choices=["f64", "f32"], default="f64")
    ap.add_argument("--seed", type=int, default=20100601)
    a = ap.parse_args(argv)
    cases = generate(a.seed)
    if a.out:
        write(cases, a.out)
        print(f"wrote {len(cases)} cases to {a.out}")
    if a.check:
        res, summary = parse(Path(a.check).read_text())
        bad = compare(cases, res, a.precision)
        for b in bad:
            print(b)
        print(f"{len(cases) - len(bad)} of {len(cases)} cases match the reference ({summary})")
        return 1 if bad else 0
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
