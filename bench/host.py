"""Host throughput of the integrator: updates per second of the C batch call
(att_integ_batch / att_integ_rk4_batch) per method, f64 and f32, against the
vectorized NumPy reference, a per-sample Python loop over
attitude_c.Integrator.update and imufusion's per-sample update; and the
public attitude_c.integrate() against the raw C call, with fresh and with
reused output buffers."""

from __future__ import annotations

import time
from typing import Any, Callable

import numpy as np

from attitude_c.names import samples_per_update

TITLE = "Host integrator throughput (C batch call vs NumPy, Python loops, imufusion)"



def _best(fn: Callable[[], Any], repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def _increments(n: int) -> np.ndarray:
    t = np.arange(n) * 1e-3
    w = np.stack([0.6 * np.sin(7 * t), 0.5 * np.cos(13 * t) + 0.3, 0.7 * np.sin(4 * t + 1)], -1)
    return w * 1e-3  # ~1 rad/s at 1 kHz


def _outputs(method: str, n: int) -> int:
    from attitude_c import method_code
    from attitude_c._lib import ffi_lib

    ffi, lib = ffi_lib("f64")
    s = ffi.new("att_integ *")
    lib.att_integ_init(s, method_code(method, lib), ffi.NULL)
    return int(lib.att_integ_outputs(s, n))


def _samples(method: str, precision: str, n: int) -> np.ndarray:
    """n increments (rates for rk4) in the precision's own dtype."""
    dt = np.float64 if precision == "f64" else np.float32
    return np.ascontiguousarray(_increments(n) * (1e3 if method == "rk4" else 1.0), dtype=dt)


def _c_runner(method: str, precision: str, n: int, fresh: bool) -> Callable[[], int]:
    """One raw C batch call over n samples per invocation (returns the number
    of updates), writing into one reused (M, 4) buffer, or with ``fresh`` into
    a new ``np.empty((M, 4))`` per call (as ``integrate()`` allocates its result)."""
    from attitude_c import method_code
    from attitude_c._lib import ffi_lib

    ffi, lib = ffi_lib(precision)
    x = _samples(method, precision, n)
    m = _outputs(method, n)
    reused = np.empty((m, 4), dtype=x.dtype)
    h = np.array([2e-3], dtype=x.dtype)
    s = ffi.new("att_integ *")
    nout = ffi.new("size_t *")
    err = ffi.new("size_t *")
    bufs = (ffi.from_buffer(x), ffi.from_buffer(h))  # keep x and h (and their views) alive with run
    px = ffi.cast("att_real *", bufs[0])
    ph = ffi.cast("att_real *", bufs[1])

    def run() -> int:
        assert bufs  # h is read only through ph: without this reference it could be freed
        out = np.empty((m, 4), dtype=x.dtype) if fresh else reused
        po = ffi.cast("att_real *", ffi.from_buffer(out))
        lib.att_integ_init(s, method_code(method, lib), ffi.NULL)
        if method == "rk4":
            st = lib.att_integ_rk4_batch(s, px, n, ph, 1, po, nout, err)
        else:
            st = lib.att_integ_batch(s, px, n, po, nout, err)
        assert st == 0, st
        return int(nout[0])

    return run


def _api_runner(method: str, precision: str, n: int, reuse: bool) -> Callable[[], int]:
    """One public ``attitude_c.integrate`` (``integrate_rates`` for rk4) call on
    the same n samples as :func:`_c_runner`, in the precision's own dtype
    (float32 for f32: no conversion copy); with ``reuse``, into one buffer
    passed as ``out=``."""
    import attitude_c as ac

    x = _samples(method, precision, n)
    buf = np.empty((_outputs(method, n), 4), dtype=x.dtype) if reuse else None

    def run() -> int:
        if method == "rk4":
            return len(ac.integrate_rates(x, 1e-3, "rk4", precision=precision, out=buf))  # type: ignore[arg-type]
        return len(ac.integrate(x, method, precision=precision, out=buf))  # type: ignore[arg-type]

    return run


def _rate(run: Callable[[], int], repeat: int) -> float:
    box = [0]
    sec = _best(lambda: box.__setitem__(0, run()), repeat)
    return box[0] / sec


def c_batch_rate(method: str, precision: str, n: int, repeat: int, fresh: bool = False) -> float:
    """Attitude updates per second of one raw C batch call over n samples."""
    return _rate(_c_runner(method, precision, n, fresh), repeat)


def integrate_rate(method: str, precision: str, n: int, repeat: int, reuse: bool = False) -> float:
    """Attitude updates per second of the public call (see :func:`_api_runner`)."""
    return _rate(_api_runner(method, precision, n, reuse), repeat)


#: integrate() must stay within this fraction of the raw C call (issue 12).
INTEGRATE_TARGET = 0.85


def api_rates(method: str, precision: str, n: int, repeat: int) -> dict[str, float]:
    """Both fair pairings of the public call and the raw C call: a fresh output
    array each call (``integrate()`` vs raw C + ``np.empty``) and one reused
    buffer (``integrate(out=buf)`` vs raw C into one buffer). The four are
    timed interleaved, run by run, so that the machine's load drifts over all
    of them alike; best of ``repeat`` each."""
    runs = {"c_fresh": _c_runner(method, precision, n, fresh=True),
            "api_fresh": _api_runner(method, precision, n, reuse=False),
            "c_reuse": _c_runner(method, precision, n, fresh=False),
            "api_reuse": _api_runner(method, precision, n, reuse=True)}
    best = dict.fromkeys(runs, 0.0)
    for _ in range(repeat):
        for k, run in runs.items():
            best[k] = max(best[k], _rate(run, 1))
    return best


def numpy_rate(method: str, n: int, repeat: int) -> float:
    from attitude_c import reference as ref

    d = _increments(n)
    if method == "rk4":
        sec = _best(lambda: ref.integrate_rates(d * 1e3, 1e-3), repeat)
    else:
        sec = _best(lambda: ref.integrate(d, method), repeat)
    return (n // samples_per_update(method)) / sec


def python_loop_rate(method: str, n: int) -> float:
    import attitude_c as ac

    d = _increments(n)
    it = ac.Integrator(method)
    if method == "rk4":
        rows = list(d * 1e3)
        t0 = time.perf_counter()
        for r in rows:
            it.update(r, dt=1e-3)
    else:
        rows = list(d)
        t0 = time.perf_counter()
        for r in rows:
            it.update(r)
    sec = time.perf_counter() - t0
    return (n // samples_per_update(method)) / sec


def imufusion_rate(n: int) -> float | None:
    try:
        import imufusion
    except ImportError:
        return None
    ahrs = imufusion.Ahrs()
    ahrs.set_sample_period(1e-3)
    g = list(np.degrees(_increments(n) * 1e3))
    acc = np.array([0.0, 0.0, 1.0])
    t0 = time.perf_counter()
    for r in g:
        ahrs.update_no_magnetometer(r, acc)
    return n / (time.perf_counter() - t0)


def _fmt(r: float | None) -> str:
    if r is None:
        return "n/a"
    return f"{r / 1e6:.2f} M" if r >= 1e6 else f"{r / 1e3:.0f} k"


def run(quick: bool = False) -> str:
    from attitude_c import METHODS

    n = 300_000 if quick else 3_000_000
    repeat = 2 if quick else 5
    n_loop = 3_000 if quick else 30_000
    rows = []
    rates: dict[tuple[str, str], float] = {}
    for m in METHODS:
        f64 = c_batch_rate(m, "f64", n, repeat)
        f32 = c_batch_rate(m, "f32", n, repeat)
        npy = numpy_rate(m, n // 10, max(1, repeat // 2))
        loop = python_loop_rate(m, n_loop)
        rates[m, "f64"], rates[m, "numpy"], rates[m, "loop"] = f64, npy, loop
        gyro = f64 * samples_per_update(m)
        rows.append(f"| {m} | {_fmt(f64)} | {_fmt(gyro)} | {_fmt(f32)} | {_fmt(npy)} | "
                    f"{f64 / npy:.0f}× | {_fmt(loop)} |")
    fus = imufusion_rate(n_loop)
    rv3 = rates["rv3", "f64"]
    api_rows = []
    api_ok = True
    for m in METHODS:
        for p in ("f64", "f32"):
            r = api_rates(m, p, n, repeat)
            fr, rr = r["api_fresh"] / r["c_fresh"], r["api_reuse"] / r["c_reuse"]
            api_ok = api_ok and min(fr, rr) >= INTEGRATE_TARGET
            api_rows.append(f"| {m} | {p} | {_fmt(r['c_fresh'])} | {_fmt(r['api_fresh'])} | {fr:.2f} | "
                            f"{_fmt(r['c_reuse'])} | {_fmt(r['api_reuse'])} | {rr:.2f} |")
    out = [
        (f"Samples per call: {n:,} increments (~1 rad/s at 1 kHz); best of {repeat}. "
        "Updates/s count attitude outputs (rv2: one per 2 increments, rv3 and rv3-coning: one per 3, "
        "rk4: one per 2 rate rows). The C figures time one raw `att_integ_batch` / "
        "`att_integ_rk4_batch` call through CFFI (input checks are in the call: NaN/Inf abort it); "
        "the public `attitude_c.integrate` wraps it (second table below)."),
        "",
        ("| method | C f64 updates/s | gyro samples/s | C f32 updates/s | NumPy reference updates/s "
        "| C f64 / NumPy | Python loop, one `Integrator.update` call per sample, updates/s |"),
        "|---|---|---|---|---|---|---|",
        *rows,
        "",
        (f"imufusion (x-io Fusion, `Ahrs.update_no_magnetometer` per sample, Python loop): "
        f"{_fmt(fus)} updates/s."),
        "",
        (f"The public call against the raw C call it wraps, {n:,} samples in the precision's own dtype "
         "(float32 for f32), `integrate_rates` for rk4, in two fair pairings: *fresh*, the raw call "
         "writing into a new `np.empty((M, 4))` allocated in each timed run against `integrate()` "
         "(which returns a new array), and *reused*, the raw call writing into one buffer against "
         "`integrate(out=buf)`. The C call checks every sample itself, so the public call adds only "
         "argument checks and the call; a fresh output array adds the first touch of its pages "
         "(largest with one output per increment: rv1, rv3-reuse, 96 MB of quaternions in f64). "
         f"Best of {repeat} runs each, the four timed interleaved; ratio = public / raw."),
        "",
        ("| method | precision | C, fresh buffer | `integrate()` | ratio | C, reused buffer "
         "| `integrate(out=)` | ratio |"),
        "|---|---|---|---|---|---|---|---|",
        *api_rows,
        "",
        (f"Target of issue 12: the public call within {100 * (1 - INTEGRATE_TARGET):.0f} % of the raw C "
         f"call in both pairings, every method, f64 and f32 → **{'met' if api_ok else 'NOT met'}**."),
        "",
        f"Targets of issue 2 for rv3 f64: ≥ 10 M updates/s → **{_fmt(rv3)}** "
        f"({'met' if rv3 >= 10e6 else 'NOT met'}); ≥ 20× the NumPy reference → "
        f"**{rv3 / rates['rv3', 'numpy']:.0f}×**; ≥ 30× imufusion per sample → "
        + (f"**{rv3 / fus:.0f}×**." if fus else "imufusion not installed."),
    ]
    return "\n".join(out)


if __name__ == "__main__":  # pragma: no cover
    print(run(quick=True))
