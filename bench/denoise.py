"""Wavelet threshold denoising: the FPGA+DSP paper's static gyro test in
simulation (sec. 3.4, Fig. 5–6), what the denoiser does and does not do to
the attitude, a 5 °/s turntable run (sec. 4.2), the design choices, the
ARMv4T cost and the host throughput against PyWavelets.

The gyro is the simulator's model (``attitude_c.sim.sensors``: GyroModel,
rate_noise) in the rate domain, no ADC: the paper's ADIS16488 delivers
digital rates over SPI. Its white rate noise is scaled so that the raw
record spans about the ±0.04 °/s of the paper's Fig. 5 (0.0007 °/s/√Hz,
σ ≈ 0.01 °/s at 200 Hz); the ratios below do not depend on that scale.
The two presets of the simulator (cg-l53, adxrs150: first-order filtered,
i.e. coloured, noise) are run too.

    python -m bench.denoise [--quick] [--no-timing]    # Markdown on stdout
    invoke bench --only denoise                        # docs/bench/denoise.md

``--no-timing`` leaves out the host throughput (figures from a loaded
machine would be wrong); everything else is exact or seeded.
"""

from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

TITLE = "Wavelet threshold denoising: the static gyro test, attitude error, ARMv4T cost, throughput"

RATE_HZ = 200.0
DT = 1.0 / RATE_HZ
STATIC_S = 100.0          # sec. 3.4: 200 Hz for 100 s
TURNTABLE_S = 360.0       # sec. 4.2: 5 °/s about z for 360 s
TURNTABLE_DPS = 5.0
CALIBRATION_S = 10.0      # at rest before a run: the turn-on bias is its mean rate
SEED = 20210501
DEG = math.pi / 180.0
PLOT = ROOT / "docs" / "img" / "denoise-static.png"


def fig5_gyro() -> Any:
    """ADIS16488-like rate gyro, white noise scaled to the paper's Fig. 5 spread."""
    from attitude_c.sim.sensors import GyroModel

    return GyroModel("fig5", range_dps=450.0, scale_v_per_dps=1.0, null_v=0.0, bias_dps=0.1,
                     noise_density=0.0007, bandwidth_hz=None)


def gyros() -> dict[str, Any]:
    from attitude_c.sim.sensors import gyro_preset

    return {"fig5": fig5_gyro(), "cg-l53": gyro_preset("cg-l53"), "adxrs150": gyro_preset("adxrs150")}


def _streams(seed: int) -> tuple[np.random.Generator, np.random.Generator, np.random.Generator]:
    """Independent streams for the turn-on bias, the run's noise and the calibration's noise."""
    a, b, c = np.random.SeedSequence(seed).spawn(3)
    return np.random.default_rng(a), np.random.default_rng(b), np.random.default_rng(c)


def measure(omega: np.ndarray, gyro: Any, bias: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Gyro output (rad/s): true rate + turn-on bias + the model's rate noise."""
    from attitude_c.sim.sensors import rate_noise

    return omega + bias + rate_noise(len(omega), DT, gyro, rng)


def _angles(q: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Attitude-angle error (deg) between estimates and truth, (n, 4) each."""
    import attitude_c as ac

    d = ac.quat_multiply(ac.quat_conj(truth), q)
    return np.degrees(2 * np.arctan2(np.linalg.norm(d[:, 1:], axis=1), np.abs(d[:, 0])))


def _integrate(rates: np.ndarray, q0: np.ndarray) -> np.ndarray:
    """Attitude after each sample (rv1: one update per increment Δθ = ω·dt)."""
    import attitude_c as ac

    return ac.integrate(rates * DT, method="rv1", q0=q0)


def static_experiment(config: Any = None, gyro: Any = None, seed: int = SEED,
                      precision: str = "f64") -> dict[str, Any]:
    """The paper's test: the gyro at rest, 200 Hz, 100 s. Noise figures per
    axis before and after; the attitude from raw and denoised rates, with the
    turn-on bias left in and calibrated out (mean of a 10 s record at rest,
    denoised the same way)."""
    from attitude_c.denoise import DenoiseConfig, denoise

    cfg = config or DenoiseConfig()
    gyro = gyro or fig5_gyro()
    rb, rn, rc = _streams(seed)
    n = round(STATIC_S * RATE_HZ)
    bias = rb.normal(0.0, gyro.bias_dps, 3) * DEG
    x = measure(np.zeros((n, 3)), gyro, bias, rn)
    y = denoise(x, cfg, precision=precision)
    cal_x = measure(np.zeros((int(CALIBRATION_S * RATE_HZ), 3)), gyro, bias, rc)
    b_raw = cal_x.mean(axis=0)
    b_dn = denoise(cal_x, cfg, precision=precision).mean(axis=0)
    truth = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
    q0 = truth[0]
    err = {
        "raw": _angles(_integrate(x, q0), truth),
        "denoised": _angles(_integrate(y, q0), truth),
        "raw, calibrated": _angles(_integrate(x - b_raw, q0), truth),
        "denoised, calibrated": _angles(_integrate(y - b_dn, q0), truth),
    }
    # the two solutions differ only inside output segments (segment sums are kept)
    q_raw, q_dn = _integrate(x - b_raw, q0), _integrate(y - b_dn, q0)
    between = _angles(q_dn, q_raw)
    return {
        "config": cfg, "gyro": gyro.name, "n": n, "t": np.arange(1, n + 1) * DT,
        "x_dps": x / DEG, "y_dps": y / DEG, "bias_dps": bias / DEG,
        "ptp_raw": np.ptp(x, axis=0) / DEG, "ptp_dn": np.ptp(y, axis=0) / DEG,
        "rms_raw": np.std(x, axis=0) / DEG, "rms_dn": np.std(y, axis=0) / DEG,
        "mean_raw": x.mean(axis=0) / DEG, "mean_dn": y.mean(axis=0) / DEG,
        "scale_dps": float(np.max(np.abs(x))) / DEG,
        "calibration_dps": (b_raw / DEG, b_dn / DEG),
        "err": err, "between_max_deg": float(between.max()),
    }


def turntable_experiment(config: Any = None, gyro: Any = None, seed: int = SEED,
                         precision: str = "f64") -> dict[str, Any]:
    """5 °/s about z for 360 s after a 10 s calibration at rest. The attitude
    error of raw rates, of denoised rates aligned with them (post-processing)
    and of denoised rates as a real-time system gets them (each sample
    ``latency`` samples late)."""
    from attitude_c.denoise import DenoiseConfig, denoise
    from attitude_c.sim.trajectory import ConstantRateTrajectory

    cfg = config or DenoiseConfig()
    gyro = gyro or fig5_gyro()
    rb, rn, rc = _streams(seed)
    traj = ConstantRateTrajectory(rate=(0.0, 0.0, TURNTABLE_DPS * DEG))
    n = round(TURNTABLE_S * RATE_HZ)
    t = np.arange(n) * DT
    bias = rb.normal(0.0, gyro.bias_dps, 3) * DEG
    # the table turns at a constant rate: every sample's mean rate is the rate
    x = measure(traj.omega(t), gyro, bias, rn)
    cal_x = measure(np.zeros((int(CALIBRATION_S * RATE_HZ), 3)), gyro, bias, rc)
    y = denoise(x, cfg, precision=precision)
    b_raw = cal_x.mean(axis=0)
    b_dn = denoise(cal_x, cfg, precision=precision).mean(axis=0)
    truth = traj.quat(t + DT)
    q0 = traj.quat(0.0)
    q_raw, q_dn = _integrate(x - b_raw, q0), _integrate(y - b_dn, q0)
    lat = cfg.latency
    q_rt = np.vstack([np.tile(q0, (lat, 1)), q_dn[: n - lat]])  # what is known at each instant
    err = {"raw": _angles(q_raw, truth), "denoised (post-processed)": _angles(q_dn, truth),
           "denoised (real time)": _angles(q_rt, truth)}
    return {"config": cfg, "gyro": gyro.name, "n": n, "err": err, "latency": lat,
            "rms_raw": float(np.std(x[:, 2]) / DEG), "rms_dn": float(np.std(y[:, 2]) / DEG)}


def design_table(seed: int = SEED, seconds: float = 60.0) -> list[tuple[str, float, float, float]]:
    """Rate error of a moving gyro (the simulator's sinusoidal ``paper``
    trajectory, 200 Hz, Fig. 5 noise) after denoising, relative to the raw
    noise, for the defaults and the alternatives docs/denoise.md discusses.
    Rows: (configuration, latency s, RMS error ratio, max error ratio); the
    first and the last 128 samples (the record's own edges) are left out."""
    from attitude_c.denoise import DenoiseConfig, denoise
    from attitude_c.sim.trajectory import PaperTrajectory

    _, rn, _ = _streams(seed)
    n = int(seconds * RATE_HZ)
    # the mean rate of each interval (what a sampled-and-averaged gyro gives)
    omega = PaperTrajectory().increments(0.0, DT, n) / DT
    x = measure(omega, fig5_gyro(), np.zeros(3), rn)
    inner = slice(128, n - 128)
    noise = (x - omega)[inner]
    variants = [
        ("defaults (db4, L 4, N 128, Es 56, Ee 24, soft, detrend)", DenoiseConfig()),
        ("symmetric edges Es = Ee = 40", DenoiseConfig(edge_start=40, edge_end=40)),
        ("no overlap (Es = Ee = 0)", DenoiseConfig(edge_start=0, edge_end=0)),
        ("no detrending", DenoiseConfig(detrend=False)),
        ("hard threshold", DenoiseConfig(threshold="hard")),
        ("haar", DenoiseConfig(wavelet="haar")),
        ("db2", DenoiseConfig(wavelet="db2")),
        ("N 64, L 3, Es 24, Ee 8", DenoiseConfig(levels=3, block=64, edge_start=24, edge_end=8)),
        ("N 128, L 3, Es 56, Ee 24", DenoiseConfig(levels=3)),
        ("N 256, L 5, Es 112, Ee 48", DenoiseConfig(levels=5, block=256, edge_start=112, edge_end=48)),
    ]
    rows = []
    for label, cfg in variants:
        e = (denoise(x, cfg) - omega)[inner]
        rows.append((label, cfg.latency_s(RATE_HZ), float(np.sqrt(np.mean(e ** 2) / np.mean(noise ** 2))),
                     float(np.max(np.abs(e)) / np.max(np.abs(noise)))))
    return rows


def edge_profile(seed: int = SEED, blocks: int = 400) -> np.ndarray:
    """RMS rate error (relative to the raw noise) at each position of a block
    when the moving-gyro record is cut into non-overlapping default blocks:
    where the wrap disturbs the estimate, hence the edges that are dropped."""
    from attitude_c.denoise import DenoiseConfig, denoise
    from attitude_c.sim.trajectory import PaperTrajectory

    cfg = DenoiseConfig(edge_start=0, edge_end=0)
    _, rn, _ = _streams(seed)
    n = cfg.block * blocks
    omega = PaperTrajectory().increments(0.0, DT, n) / DT
    x = measure(omega, fig5_gyro(), np.zeros(3), rn)
    e = denoise(x, cfg) - omega
    s = np.sqrt(np.mean((x - omega) ** 2))
    return np.sqrt(np.mean(e.reshape(blocks, cfg.block, 3) ** 2, axis=(0, 2))) / s


def plot_static(res: dict[str, Any], path: Path = PLOT) -> Path:
    """Fig. 5–6 of the paper for the simulation: y-axis rate before and after."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from attitude_c._io import write_with

    t, x, y = res["t"], res["x_dps"][:, 1], res["y_dps"][:, 1]
    b = res["mean_raw"][1]
    fig, axes = plt.subplots(2, 1, figsize=(8, 5), sharex=True, sharey=True)
    for ax, v, title in ((axes[0], x, "raw (cf. Fig. 5)"), (axes[1], y, "wavelet threshold denoised (cf. Fig. 6)")):
        ax.plot(t, v - b, lw=0.4)
        ax.axhline(v.max() - b, color="k", lw=0.6, ls=":")
        ax.axhline(v.min() - b, color="k", lw=0.6, ls=":")
        ax.set_title(f"static gyro, y axis, 200 Hz: {title}; peak-to-peak {np.ptp(v):.4f} °/s", fontsize=9)
        ax.set_ylabel("rate − mean (°/s)")
        ax.grid(alpha=0.3)
    axes[1].set_xlabel("time (s)")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        write_with(path, lambda tmp: fig.savefig(tmp, dpi=110, format="png"))
    finally:
        plt.close(fig)
    return path


# -- ARMv4T instruction counts ---------------------------------------------------------

COUNT_CONFIGS = [
    ("db4", "soft", 4, 128, 56, 24),
    ("db4", "hard", 4, 128, 56, 24),
    ("db2", "soft", 4, 128, 56, 24),
    ("haar", "soft", 4, 128, 56, 24),
    ("db4", "soft", 4, 128, 0, 0),
    ("db4", "soft", 3, 64, 24, 8),
]


def armv4t_counts(quick: bool) -> list[tuple[str, str, float, float, float]]:
    """(configuration, precision, instructions per sample per axis, per window,
    per sample between windows) on the emulated ARM920T (exact counts)."""
    from toolchain import targets as T
    from toolchain.qemu_count import per_iteration

    t = T.load("armv4t-bare")
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for prec in ("f64", "f32"):
            exe = t.build_program([ROOT / "csrc" / "vectors" / "bench_denoise.c"], Path(d) / f"bench_denoise_{prec}",
                                  defines=["ATT_REAL_F32"] if prec == "f32" else [])
            for w, mode, lv, block, es, ee in COUNT_CONFIGS:
                hop = block - es - ee
                k = 2 if quick else 10  # windows between the two runs

                def args(m: int, w: str = w, mode: str = mode, lv: int = lv, block: int = block,
                         es: int = es, ee: int = ee) -> list[str]:
                    return [w, mode, str(lv), str(block), str(es), str(ee), f"{m:06d}"]

                base = block + 2 * hop
                per_sample = per_iteration(exe, args, base, base + k * hop)
                between = per_iteration(exe, args, base + 1, base + hop - 1)
                rows.append((f"{w} {mode} L{lv} N{block} Es{es} Ee{ee}", prec, per_sample, per_sample * hop,
                             between))
    return rows


# -- host throughput (run on a quiet machine) ----------------------------------------------

def pywt_stream(x: np.ndarray, cfg: Any) -> np.ndarray:
    """The same windowed denoiser with PyWavelets doing each block (the
    segment bookkeeping of attitude_c.denoise.reference.windows)."""
    import pywt

    from attitude_c.denoise.reference import windows

    n = cfg.block
    t = np.arange(n) - (n - 1) / 2
    s2 = float(np.sum(t * t))
    y = np.empty_like(x)
    for w in windows(len(x), n, cfg.edge_start, cfg.edge_end):
        u = x[w.start: w.start + n]
        line = u.mean(axis=0) + np.outer(t, t @ u / s2) if cfg.detrend else 0.0
        c = pywt.wavedec(u - line, cfg.wavelet, mode="periodization", level=cfg.levels, axis=0)
        lam = np.median(np.abs(c[-1]), axis=0) / 0.6744897501960817 * math.sqrt(2 * math.log(n))
        v = pywt.waverec([c[0]] + [pywt.threshold(d, lam, mode=cfg.threshold) for d in c[1:]],
                         cfg.wavelet, mode="periodization", axis=0) + line
        seg = slice(w.out_start - w.start, w.out_stop - w.start)
        y[w.out_start: w.out_stop] = v[seg] + (u[seg].sum(axis=0) - v[seg].sum(axis=0)) / (w.out_stop - w.out_start)
    return y


def throughput(quick: bool) -> list[tuple[str, float]]:
    """(what, samples per second per axis) on the host."""
    import pywt

    from attitude_c.denoise import DenoiseConfig, denoise, wavedec, waverec

    from .host import _best  # best of a few runs, time.perf_counter

    cfg = DenoiseConfig()
    reps = 2 if quick else 5
    n = 20_000 if quick else 200_000
    rng = np.random.default_rng(1)
    x = 0.01 + 1e-3 * rng.normal(size=(n, 3))
    rows = [
        ("attitude_c.denoise.denoise, f64, 3 axes", 3 * n / _best(lambda: denoise(x, cfg), reps)),
        ("attitude_c.denoise.denoise, f32, 3 axes", 3 * n / _best(lambda: denoise(x, cfg, precision="f32"), reps)),
        ("the same windows with PyWavelets per block (pywt_stream), 3 axes",
         3 * n / _best(lambda: pywt_stream(x, cfg), max(1, reps // 2))),
    ]
    big = rng.normal(size=16384)
    m = 50 if quick else 500
    ours = _best(lambda: [waverec(wavedec(big, "db4", 3), "db4") for _ in range(m // 10)], reps)
    theirs = _best(lambda: [pywt.waverec(pywt.wavedec(big, "db4", mode="periodization", level=3), "db4",
                                         mode="periodization") for _ in range(m // 10)], reps)
    rows.append(("one 16 384-sample block, db4 L3 there and back: attitude_c", len(big) * (m // 10) / ours))
    rows.append(("one 16 384-sample block, db4 L3 there and back: PyWavelets", len(big) * (m // 10) / theirs))
    return rows


# -- report --------------------------------------------------------------------------------

def _fmt_axes(v: np.ndarray, digits: int = 4) -> str:
    return " / ".join(f"{a:.{digits}f}" for a in v)


def run(quick: bool = False, timing: bool = True) -> str:
    out: list[str] = []
    from attitude_c.denoise import DenoiseConfig

    cfg = DenoiseConfig()
    out.append(f"Defaults: {cfg.wavelet}, {cfg.levels} levels, block N = {cfg.block}, edges Es = "
               f"{cfg.edge_start}, Ee = {cfg.edge_end} (hop {cfg.hop}), {cfg.threshold} threshold, detrend "
               f"{cfg.detrend}; latency "
               f"{cfg.latency} samples = {cfg.latency_s(RATE_HZ) * 1e3:.0f} ms at {RATE_HZ:.0f} Hz. "
               f"Seed {SEED}; rate-domain gyro model of `attitude_c.sim.sensors` (module docstring).\n")
    out.append("**Static gyro, 200 Hz, 100 s (paper sec. 3.4, Fig. 5–6: y-axis spread ±0.04 → ±0.02 °/s).** "
               "Per axis x / y / z, °/s; RMS about the mean.\n")
    out.append("| gyro | ptp raw | ptp denoised | ptp ratio | RMS raw | RMS denoised | RMS ratio | "
               "|mean change| / max|x| |")
    out.append("|---|---|---|---|---|---|---|---|")
    res_main = None
    for name, gyro in gyros().items():
        r = static_experiment(cfg, gyro)
        if name == "fig5":
            res_main = r
        dm = np.abs(r["mean_dn"] - r["mean_raw"]) / r["scale_dps"]
        out.append(f"| {name} | {_fmt_axes(r['ptp_raw'])} | {_fmt_axes(r['ptp_dn'])} | "
                   f"{_fmt_axes(r['ptp_dn'] / r['ptp_raw'], 3)} | {_fmt_axes(r['rms_raw'])} | "
                   f"{_fmt_axes(r['rms_dn'])} | {_fmt_axes(r['rms_dn'] / r['rms_raw'], 3)} | "
                   f"{max(dm):.1e} |")
    assert res_main is not None
    plot_static(res_main)
    out.append(f"\nPlot: `docs/img/denoise-static.png` (fig5 gyro, y axis). Turn-on bias of that run "
               f"{_fmt_axes(res_main['bias_dps'])} °/s, passed through unchanged.\n")
    out.append("**Attitude from the static record** (rv1 at 200 Hz; error angle in degrees at 100 s and its RMS "
               "over the run). *calibrated*: minus the mean rate of a separate 10 s record at rest, "
               "denoised the same way for the denoised solution.\n")
    out.append("| rates | error at 100 s | RMS error |")
    out.append("|---|---|---|")
    for k, e in res_main["err"].items():
        out.append(f"| {k} | {e[-1]:.5f} | {np.sqrt(np.mean(e ** 2)):.5f} |")
    out.append(f"\nLargest angle between the raw and the denoised calibrated solutions over the run: "
               f"{res_main['between_max_deg']:.2e}°.\n")
    tt = turntable_experiment(cfg)
    out.append(f"**Turntable: {TURNTABLE_DPS:.0f} °/s about z for {TURNTABLE_S:.0f} s** (paper sec. 4.2), "
               f"fig5 gyro, after a 10 s calibration at rest; z-rate RMS noise {tt['rms_raw']:.4f} → "
               f"{tt['rms_dn']:.4f} °/s. *real time*: each denoised sample arrives {tt['latency']} samples late.\n")
    out.append("| rates | max error ° | RMS error ° | error at 360 s ° |")
    out.append("|---|---|---|---|")
    for k, e in tt["err"].items():
        out.append(f"| {k} | {e.max():.5f} | {np.sqrt(np.mean(e ** 2)):.5f} | {e[-1]:.5f} |")
    out.append("\n**Design choices on a moving gyro** (the simulator's sinusoidal `paper` trajectory at 200 Hz, "
               "60 s, fig5 noise): rate error after denoising relative to the raw noise (RMS and max), the "
               "record's first and last 128 samples left out.\n")
    out.append("| configuration | latency s | RMS error ratio | max error ratio |")
    out.append("|---|---|---|---|")
    for label, lat, rms, mx in design_table(seconds=20.0 if quick else 60.0):
        out.append(f"| {label} | {lat:.3f} | {rms:.3f} | {mx:.3f} |")
    prof = edge_profile(blocks=100 if quick else 400)
    out.append("\nRate error by position in a block when the record is cut into non-overlapping default "
               "blocks (RMS relative to the raw noise, positions 0…127, the newest last): the periodic wrap "
               "disturbs the first ~56 and the last ~24 samples, hence Es = 56, Ee = 24.\n")
    out.append("```")
    for i in range(0, len(prof), 16):
        out.append(f"{i:2d}: " + " ".join(f"{v:.2f}" for v in prof[i: i + 16]))
    out.append("```")
    out.append("\n**ARMv4T (ARM920T) instructions per sample per axis** (`qemu-arm -cpu ti925t`, exact counts, "
               "`csrc/vectors/bench_denoise.c`: one `att_wden_push` per sample, static gyro data; difference of two "
               "runs whose lengths differ by whole hops; soft-float newlib, `-O2`). Per window = per sample × hop; "
               "between windows = a push that completes no window.\n")
    out.append("| configuration | precision | per sample | per window | between windows | µs/sample @400 MHz, CPI 1.5 |")
    out.append("|---|---|---|---|---|---|")
    for label, prec, ps, pw, bw in armv4t_counts(quick):
        out.append(f"| {label} | {prec} | {ps:,.0f} | {pw:,.0f} | {bw:,.0f} | {ps * 1.5 / 400e6 * 1e6:.1f} |")
    if timing:
        out.append("\n**Host throughput** (samples per second, best of a few runs, `time.perf_counter`).\n")
        out.append("| what | samples/s |")
        out.append("|---|---|")
        for label, sps in throughput(quick):
            out.append(f"| {label} | {sps:,.0f} |")
    else:
        out.append("\nHost throughput: not measured in this run (`--no-timing`).")
    return "\n".join(out)


if __name__ == "__main__":  # pragma: no cover
    print(run(quick="--quick" in sys.argv, timing="--no-timing" not in sys.argv))
