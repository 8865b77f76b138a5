"""attitude-rx under faults: back-pressure against the senders' answer timeout,
a slow consumer, and line noise through the legacy protocol.

Method. attitude-rx (host build of the tree) runs on a pty; the sender is
``attitude_c.link.transport.run_sender`` (the loop of ``attitude link-tx``)
with the C machine (the firmware's sender code) or the Python one, on the
pty's master side, with the answer timeout of the firmware and of link-tx
(50 ms) and 5 attempts, skipping a block it gave up on (the firmware's
behaviour). The back-pressure and slow-consumer figures are wall-clock
runs: on a loaded machine the counts move (the answer latency adds to the
hold), the pattern does not. The noise figures are exact counts
(``bench/link_noise.c``: the C receiver B and the block decoder over
seeded random bytes).
"""

from __future__ import annotations

import fcntl
import json
import os
import select
import signal
import struct
import subprocess
import tempfile
import termios
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TITLE = "attitude-rx under faults (back-pressure, slow consumer, line noise)"

ANSWER_TIMEOUT_MS = 50  # firmware/config.h FW_ANSWER_TIMEOUT_TICKS (180 / 3600 s) and link-tx's default
DELAY = 0.1  # s per record in the attitude thread: room in the queue comes later than the answer timeout
HOLDS = (0, 10, 20, 30, 40, 45, 60, 100)  # --hold-ms tried


class FdPort:
    """The master side of a pty as the small part of a pyserial port that run_sender uses."""

    def __init__(self, fd: int) -> None:
        self.fd = fd
        self.timeout: float | None = 0.005
        self.name = f"pty fd {fd}"

    @property
    def in_waiting(self) -> int:
        return struct.unpack("i", fcntl.ioctl(self.fd, termios.FIONREAD, b"\0\0\0\0"))[0]

    def read(self, n: int) -> bytes:
        r, _, _ = select.select([self.fd], [], [], self.timeout)
        return os.read(self.fd, n) if r else b""

    def write(self, data: bytes) -> None:
        os.write(self.fd, data)

    def flush(self) -> None:
        pass


def _stats(err: str) -> dict[str, int]:
    out: dict[str, int] = {}
    for line in err.splitlines():
        if line.startswith(("attitude-rx: link:", "attitude-rx: samples:")):
            for kv in line.split(":", 2)[2].split():
                k, v = kv.split("=")
                out[k] = int(v)
    return out


def _codes(n: int) -> list[tuple[int, int, int]]:
    return [(1000 + i % 2000, 2048 + i % 7, 3000 - i % 2000) for i in range(n)]


def _block(c: tuple[int, int, int]) -> bytes:
    return b"".join(v.to_bytes(2, "big") for v in c)


def rx_run(exe: str, rx_args: list[str], n: int, impl: str = "c", read_after: float = 0.0,
           max_attempts: int = 5) -> dict[str, float]:
    """attitude-rx with rx_args, n unique sample blocks from run_sender; its stdout is a pipe
    nobody reads for read_after s, then drained. Returns the counts on both sides."""
    from attitude_c.link.transport import run_sender

    master, slave = os.openpty()
    proc = subprocess.Popen([exe, "--port", os.ttyname(slave), "--method", "rv1", "--no-header",
                             "--gap-ms", "1000", *rx_args], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    out = bytearray()
    t_read = time.monotonic() + read_after

    def reader() -> None:
        assert proc.stdout is not None
        time.sleep(max(0.0, t_read - time.monotonic()))
        while (b := os.read(proc.stdout.fileno(), 65536)):
            out.extend(b)

    th = threading.Thread(target=reader, daemon=True)
    try:
        assert proc.stderr is not None
        banner = b""
        while b"8N1" not in banner:
            banner += os.read(proc.stderr.fileno(), 4096)
        th.start()
        t0 = time.monotonic()
        _, a = run_sender(FdPort(master), [_block(c) for c in _codes(n)], impl=impl,
                                answer_timeout_ms=ANSWER_TIMEOUT_MS, max_attempts=max_attempts,
                                on_give_up="skip")
        dt = time.monotonic() - t0
        time.sleep(max(0.3, t_read - time.monotonic() + 0.3))
        proc.send_signal(signal.SIGINT)
        err = proc.stderr.read().decode()
        proc.wait(timeout=60)
        th.join(60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        os.close(master)
        os.close(slave)
    st = _stats(err)
    rows = [tuple(ln.split(",")[2:5]) for ln in out.decode().splitlines()]
    return {"a_accepted": a["blocks_accepted"], "a_gave_up": a["gave_up"], "a_timeouts": a["timeouts"],
            "acknowledged": st["blocks_accepted"], "integrated": st["integrated"],
            "overflows": st.get("queue_overflows", 0), "busy_naks": st.get("busy_naks", 0),
            "printed": len(rows), "duplicates": len(rows) - len(set(rows)),
            "blocks_per_s": a["blocks_accepted"] / dt, "rc": proc.returncode}


def noise(mib: int, seed: int = 1) -> dict[str, int]:
    """bench/link_noise.c: what mib MiB of random bytes become in B and the block decoder."""
    with tempfile.TemporaryDirectory() as d:
        exe = Path(d) / "link_noise"
        src = ROOT / "csrc" / "src"
        subprocess.run(["gcc", "-std=c99", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror",
                        f"-I{ROOT / 'csrc' / 'include'}", str(ROOT / "bench" / "link_noise.c"),
                        str(src / "link_receiver.c"), str(src / "block_decode.c"), str(src / "common.c"),
                        "-o", str(exe)], check=True)
        return json.loads(subprocess.run([str(exe), str(mib), str(seed)], check=True, capture_output=True,
                                         text=True).stdout)


def noise_expected_per_accepted() -> dict[str, float]:
    """Per accepted block of uniform random bytes (the data bytes of a block whose checksum
    matched are still uniform: the checksum byte is independent of them)."""
    p_mark = 1 / 256
    return {
        "good_samples": (16 / 256) ** 3,  # bytes 0, 2, 4 below 0x10 (so byte 0 is no 0xFE mark)
        "loss_reports": p_mark * (2 / 256) * (65535 / 65536)  # GAVE_UP/OVERRUN with count != 0
        + p_mark * (1 / 256) * 0.5 * (1 / 256),  # ADC_ERROR: status < 0, byte 5 = 0
    }


def _backpressure(exe: str, quick: bool) -> list[str]:
    load = os.getloadavg()[0]
    lines = [(f"Back-pressure: attitude-rx `--queue 4 --consumer-delay {DELAY:g}` (the attitude thread "
              f"takes {1 / DELAY:.0f} records/s, the sender offers more: the queue is full and a slot "
              f"frees every {DELAY * 1e3:.0f} ms, longer than the answer timeout), `--hold-ms H`; sender "
              f"answer timeout {ANSWER_TIMEOUT_MS} ms, 5 attempts, giving up on a block after them. "
              "*Duplicates*: samples printed twice (an answer that reached the sender after its "
              "timeout: it resent a block attitude-rx had acknowledged). Load average during the "
              f"runs: {load:.1f} on {os.cpu_count()} cores."),
             "",
             ("| sender | hold ms | acknowledged = printed | duplicates | A gave up | A timeouts | "
              "busy NAKs | blocks/s |"),
             "|---|---|---|---|---|---|---|---|"]
    n = 30 if quick else 80
    for impl in ("c", "python"):
        for hold in ((0, 20, 80) if quick else HOLDS):
            r = rx_run(exe, ["--queue", "4", "--consumer-delay", str(DELAY), "--hold-ms", str(hold)], n, impl)
            assert r["acknowledged"] == r["printed"] == r["integrated"], r
            lines.append(f"| {impl} | {hold} | {r['printed']} | {r['duplicates']} | {r['a_gave_up']} | "
                         f"{r['a_timeouts']} | {r['busy_naks']} | {r['blocks_per_s']:.1f} |")
    return lines


def _slow_consumer(exe: str, quick: bool) -> list[str]:
    n, wait = (300, 5.0) if quick else (2000, 25.0)
    r = rx_run(exe, [], n, "c", read_after=wait)
    return [(f"Slow consumer (issue 17): {n} samples from the C sender while stdout is a pipe nobody "
             f"reads for {wait:g} s (then drained), default options: A accepted {r['a_accepted']}, gave up "
             f"{r['a_gave_up']}; attitude-rx acknowledged {r['acknowledged']}, integrated {r['integrated']}, "
             f"printed {r['printed']} ({r['duplicates']} duplicates), {r['busy_naks']} busy NAKs.")]


def _noise(quick: bool) -> list[str]:
    mib = 256 if quick else 16384
    z = noise(mib)
    exp = noise_expected_per_accepted()
    per = 1 / mib
    loss = z["gave_up"] + z["overrun"] + z["adc_error"]
    acc = z["accepted"] * per
    return [(f"Line noise (`bench/link_noise.c`, {mib} MiB of random bytes, B back to back, N = 6): "
             f"{z['handshakes'] * per:.0f} handshakes and {acc:.2f} accepted blocks per MiB (expected "
             "2^20 / 263 / 256 = 15.57: a 0xAA every 256 bytes on average, 7 more bytes, a matching sum "
             "1 time in 256)."),
            "",
            "| accepted records decode to | count | per MiB | expected per MiB |",
            "|---|---|---|---|",
            f"| code > 4095: rejected | {z['bad_code']} | {z['bad_code'] * per:.3f} | |",
            f"| report with a bad kind or field: rejected | {z['bad_report']} | {z['bad_report'] * per:.4f} | |",
            (f"| **plausible sample: integrated** | {z['good_samples']} | {z['good_samples'] * per:.5f} | "
             f"{exp['good_samples'] * acc:.5f} |"),
            (f"| **plausible loss report: rate held over `count` periods** | {loss} | {loss * per:.5f} | "
             f"{exp['loss_reports'] * acc:.5f} |"),
            f"| plausible BOOT / SELFTEST | {z['boot']} / {z['selftest']} | | |"]


def run(quick: bool) -> str:
    from toolchain.tasks.cross import cross_build_target

    with tempfile.TemporaryDirectory() as d:
        exe = str(cross_build_target("host", out=Path(d) / "host")["app"])
        lines = [*_backpressure(exe, quick), "", *_slow_consumer(exe, quick), "", *_noise(quick)]
    return "\n".join(lines)
