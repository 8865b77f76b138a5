"""ARMv4T cost of the GNSS parser (attitude/gnss.h): instructions per NMEA sentence,
per NMEA epoch and per UBX NAV-PVT frame on the emulated ARM920T core (exact counts,
toolchain/qemu_count.py), double and float builds, and the share of a 400 MHz ARM920T
at 10 fixes/s."""

from __future__ import annotations

import functools
import tempfile
from pathlib import Path

from bench.armv4t import CLOCK_HZ, CPI
from toolchain import targets as T
from toolchain.qemu_count import per_iteration

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "bench" / "gnss_armv4t.c"
TITLE = "ARMv4T cost of the GNSS parser (instructions per NMEA sentence, per epoch, per NAV-PVT)"
RATE = 10.0  #: fixes/s of the share column (the fastest rate issue 30 names)
#: harness mode -> (what one iteration is, bytes of one iteration: bench/gnss_armv4t.c's tables)
MODES = {"rmc": ("one RMC sentence (70 bytes), closing an epoch", 70),
         "epoch": ("one epoch: RMC + VTG + GGA + GSA (229 bytes)", 229),
         "pvt": ("one NAV-PVT frame (100 bytes)", 100)}


def _args(mode: str, n: int) -> list[str]:
    return [mode, str(n)]


def run(quick: bool) -> str:
    t = T.load("armv4t-bare")
    n1, n2 = (4, 12) if quick else (10, 110)
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for prec in ("f64", "f32"):
            exe = t.build_program([SRC], Path(d) / f"gnss_{prec}", defines=["ATT_REAL_F32"] if prec == "f32" else [])
            for mode, (what, nbytes) in MODES.items():
                instr = per_iteration(exe, functools.partial(_args, mode), n1, n2)
                rows.append((prec, what, instr, instr / nbytes))
    out = [
        ("Instructions per message on the emulated ARMv4T core (`qemu-arm -cpu ti925t`, exact counts with "
        "`-singlestep -d nochain,exec`, `toolchain/qemu_count.py`; difference of two runs of "
        f"`bench/gnss_armv4t.c`, {n2 - n1} messages apart; soft-float newlib libm, `-O2`): every byte through "
        "`att_gnss_feed`, the fixes it completes included (NMEA: the velocity's cos/sin at each epoch's "
        "close). Sentences: the NMEA 0183 standard's example epoch, times alternating so that each epoch "
        f"closes. Time at 400 MHz assumes {CPI} cycles per instruction (docs/bench/armv4t.md)."),
        "",
        f"| build | message | instructions | per byte | µs @400 MHz | share @{RATE:.0f} /s |",
        "|---|---|---|---|---|---|",
    ]
    for prec, what, instr, per_byte in rows:
        us = instr * CPI / CLOCK_HZ * 1e6
        out.append(f"| {prec} | {what} | {instr:,.0f} | {per_byte:,.0f} | {us:.1f} | {us * RATE * 1e-4:.3f} % |")
    return "\n".join(out) + "\n"
