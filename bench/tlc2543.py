"""TLC2543 driver: 8051 machine cycles (s51, SDCC build) and host throughput.

8051 figures come from tests/s51/tlc2543_s51.c run in s51 (-t C51): Timer 0
counts machine cycles around each call (toolchain/s51.py). In s51 nothing
drives P1, so EOC reads "done" at once: the figures are the driver's own
cost; on hardware each cycle also waits for the conversion (<= 10 us).
"""

from __future__ import annotations

import re
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
TITLE = "TLC2543 driver (8051 machine cycles, host throughput)"
F_OSC = 11.0592e6  # AT89S51 crystal of the acquisition board (Hz)
US_PER_CYCLE = 12 / F_OSC * 1e6


def _sizes(objs: Path) -> tuple[int, int, int]:
    """(code, static RAM, overlay RAM) bytes of tlc2543.rel from its .sym area table."""
    text = (objs / "tlc2543.sym").read_text()
    size = {m.group(1): int(m.group(2), 16)
            for m in re.finditer(r"^\s+\w+\s+(\w+)\s+size\s+([0-9A-Fa-f]+)", text, re.MULTILINE)}
    return size.get("CSEG", 0) + size.get("CONST", 0), size.get("DSEG", 0), size.get("OSEG", 0)


def run(quick: bool) -> str:
    from toolchain import s51

    lines = []
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        res = s51.build_and_run([ROOT / "tests" / "s51" / "tlc2543_s51.c"], d / "tlc",
                                lib_sources=[ROOT / "csrc" / "src" / "tlc2543.c"])
        naive = s51.build_and_run([ROOT / "bench" / "tlc2543_naive_s51.c"], d / "naive")
        code, dseg, oseg = _sizes(d / "tlc.objs")
    c = dict(res.cycles)
    c["naive_cycle12"] = naive.cycles["naive_cycle12"]

    def row(label: str, key: str, per: int = 1) -> str:
        n = c[key]
        extra = f" ({n / per:.0f} per I/O cycle)" if per > 1 else ""
        return f"| {label} | {n}{extra} | {n * US_PER_CYCLE:.1f} |"

    lines += [
        ("8051 (AT89S51 model `-t C51`, SDCC 4.2 small model, s51 Timer-0 counts; "
         f"µs at {F_OSC / 1e6:.4f} MHz = {US_PER_CYCLE:.3f} µs per machine cycle):"),
        "",
        "| measurement | machine cycles | µs |",
        "| --- | --- | --- |",
        row("one 12-bit I/O cycle: `tlc2543_cycle()` call incl. argument set-up (target ≤ 150)", "cycle12"),
        row("same, textbook C loop (16-bit accumulator, loop counter)", "naive_cycle12"),
        row("X/Y/Z `tlc2543_scan()`, steady state (3 I/O cycles)", "scan_xyz_steady", 3),
        row("X/Y/Z `tlc2543_scan()` from a stale output register (4 I/O cycles)", "scan_xyz_first", 4),
        row("one 8-bit I/O cycle", "cycle8"),
        row("one 16-bit LSB-first I/O cycle (off the fast path)", "cycle16_lsbf"),
        "",
        (f"Driver size in the SDCC build: {code} bytes of code, {dseg} bytes of static internal RAM "
         f"(+ {oseg} overlayable), state 2 bytes per ADC. On hardware add the conversion wait: "
         f"EOC is polled until the ≤ 10 µs conversion ends (≈ {10 / US_PER_CYCLE:.0f} machine cycles "
         "per I/O cycle at 11.0592 MHz)."),
        "",
    ]

    # host: the same C driver against the C twin of the model, and against the Python model
    from attitude_c import tlc2543 as T

    n = 20_000 if quick else 200_000
    v = np.random.default_rng(0).uniform(0.0, 5.0, (n, 3))
    T.convert(v[:100], 5.0)
    t0 = time.perf_counter()
    T.convert(v, 5.0)
    dt = time.perf_counter() - t0
    m = T.Tlc2543Model([1.0, 2.0, 3.0], record=False)
    drv = T.Tlc2543(m)
    k = 200 if quick else 2000
    t0 = time.perf_counter()
    for _ in range(k):
        drv.scan()
    dt_py = time.perf_counter() - t0
    lines += [
        "Host (same C driver; one row = one X/Y/Z scan of 4 I/O cycles, 12-bit):",
        "",
        "| path | rows (scans) per second |",
        "| --- | --- |",
        f"| `attitude_c.tlc2543.convert` (C driver + C twin of the model), {n} rows | {n / dt:,.0f} |",
        ("| `Tlc2543(Tlc2543Model)` (C driver + Python model via CFFI callbacks, steady-state scans) "
         f"| {k / dt_py:,.0f} |"),
    ]
    return "\n".join(lines)
