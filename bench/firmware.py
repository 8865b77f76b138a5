"""AT89S51 firmware: machine cycles per scan and per block, sustained sample rate, flash and RAM.

Method: the ``bench`` image (production code, pins and RAM layout; cycle
counters kept in unused SFR cells, Timer 0 as the cycle clock) runs in
``s51 -t C51`` against libattitude's C receiver on a pty pair
(toolchain/firmware.py). In s51 nothing drives P1, so EOC reads "done" at once:
the scan figure is the driver's own cost (on hardware each of the 4 I/O
cycles also waits up to 10 us for the conversion). s51 runs in lockstep with
the host (docs/firmware.md "Lockstep"): a host answer reaches the firmware up
to one step (10 000 instructions) after the byte it answers, so the measured
exchange includes that latency; the zero-latency exchange is the measured one
minus the two waits' excess over their wire time (0xAA + 0xBB, checksum +
answer: two byte times each).
"""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TITLE = "AT89S51 firmware (machine cycles, sustained sample rate, flash and RAM)"


def _measure(tool, build_dir: Path, baud: int, blocks: int) -> dict[str, float]:  # type: ignore[no-untyped-def]
    cfg = tool.Config(baud=baud, period_ticks=144, syn_timeout=720, answer_timeout=720)
    img = tool.build(build_dir, cfg, kind="bench", sim_blocks=blocks, name=f"bench_{baud}")
    res = tool.run(img, tool.LinkHost(), timeout=300)
    b = res.bench
    n = b["blocks"]
    byte = tool.MACHINE_HZ * 10 / baud  # machine cycles per 8N1 byte
    exch = b["exch_sum"] / n
    syn_excess = max(0.0, b["syn_wait_sum"] / n - 2 * byte)
    ans_excess = max(0.0, b["ans_wait_sum"] / n - 2 * byte)
    e0 = exch - syn_excess - ans_excess
    scan = b["scan_sum"] / b["scans"]
    return {"scan": scan, "scan_min": b["scan_min"], "scan_max": b["scan_max"],
            "busy": b["busy_sum"] / n, "busy_max": b["busy_max"], "exch": exch, "e0": e0,
            "byte": byte, "line_rate": baud / 10 / tool.WIRE_BYTES_PER_BLOCK,
            "fw_rate": tool.MACHINE_HZ / (e0 + scan), "cpu_rate": tool.MACHINE_HZ / (b["busy_sum"] / n + scan),
            "max_sp": res.max_sp, "blocks": n}


def run(quick: bool) -> str:
    from toolchain import firmware as tool

    build_dir = ROOT / "build" / "bench_firmware"
    blocks = 12 if quick else 60
    prod = {baud: tool.build(build_dir, tool.Config(baud=baud), kind="production", name=f"prod_{baud}")
            for baud in (9600, 57600)}
    m = {baud: _measure(tool, build_dir, baud, blocks) for baud in (9600, 57600)}
    us = 1e6 / tool.MACHINE_HZ
    p = prod[9600]
    lines = [
        (f"Image (`invoke firmware.build`): flash **{p.flash} / 4096 bytes**, internal RAM "
         f"**{p.ram_static} / 128 bytes** static (registers, variables, bits), stack "
         f"0x{p.stack_start:02X}..0x7F = {p.stack_free} bytes; highest SP seen in s51 "
         f"0x{m[9600]['max_sp']:02X} ({0x7F - m[9600]['max_sp']} bytes never used). "
         f"The rate only changes constants: the 57600-baud image is {prod[57600].flash} bytes."),
        "",
        (f"Machine cycle = 12 clocks = {us:.3f} us at 11.0592 MHz; {blocks} blocks per rate, "
         "sampling period 40 ms (144 ticks)."),
        "",
        "| | 9600 baud | 57600 baud |",
        "|---|---:|---:|",
    ]

    def row(name: str, key: str, fmt: str = "{:.0f}") -> None:
        lines.append(f"| {name} | {fmt.format(m[9600][key])} | {fmt.format(m[57600][key])} |")

    row("X/Y/Z scan (4 I/O cycles incl. power-down), machine cycles", "scan")
    lines.append(f"| ... in us | {m[9600]['scan'] * us:.0f} | {m[57600]['scan'] * us:.0f} |")
    row("CPU cycles per block sent (link handling, all calls of one exchange)", "busy")
    row("one byte on the wire (8N1), machine cycles", "byte")
    row("exchange measured (0xAA to answer, host latency included), cycles", "exch")
    row("exchange with a zero-latency host (estimated), cycles", "e0")
    row("protocol line-rate limit (10 bytes per block), samples/s", "line_rate", "{:.1f}")
    row("firmware sustained limit 1 / (exchange + scan), samples/s", "fw_rate", "{:.1f}")
    row("CPU-only limit 1 / (block CPU + scan), samples/s", "cpu_rate", "{:.0f}")
    lines += [
        "",
        ("The firmware is one polled loop: a scan delays the next byte it hands to the UART, so "
         "the sustained limit counts scan and exchange in series. At 9600 baud the wire dominates "
         "(the firmware reaches "
         f"{100 * m[9600]['fw_rate'] / m[9600]['line_rate']:.0f} % of the protocol's line rate); at "
         "57600 baud the CPU work per byte is comparable to a byte time, so the firmware reaches "
         f"{100 * m[57600]['fw_rate'] / m[57600]['line_rate']:.0f} %. The default period (20 ms, "
         "50 samples/s) leaves room for one resend per sample at 9600 baud."),
    ]
    return "\n".join(lines)
