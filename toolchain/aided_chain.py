"""A recording through the whole aided chain (issue 26): its codes served by the TLC2543
model to the aided firmware in s51 (``data=True`` image, toolchain/firmware.py), link v2
over a pty, attitude-rx (any build: host, or ARMv4T under qemu-arm) running its filter
(``--estimator auto``, the configuration written by attitude_c.sim.board_codes) and
printing JSON lines; beside it the library's filter run directly on the same samples.

Used by tests/test_aided_chain.py (a short excerpt) and bench/chain.py (the BROAD trials).
"""

from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import tempfile
import threading
import time
import tty
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from attitude_c.link import v2
from attitude_c.sim.board_codes import BoardRecording, board_channels, resample, rx_config, values

from . import firmware as tool

#: Samples of the recording's last group repeated after it: the firmware scans ahead of
#: its acknowledgements (a ring of records), so the file must not end at the last sample.
PAD_SAMPLES = 32


@dataclass
class ChainRun:
    """What attitude-rx printed for the recording's samples, and the run's counters."""

    q: np.ndarray  #: (n, 4) attitude-rx's quaternion of sample 0..n-1
    ns: list[int]  #: the sample numbers of every attitude line printed, in order
    reports: list[dict[str, Any]]  #: every report record (BOOT, CHANNELS, losses)
    stats: dict[str, int]  #: attitude-rx's end-of-run counters (link2:, samples:, reports:)
    firmware: dict[str, int]  #: the firmware's STATS line
    sim_seconds: float
    wall_seconds: float
    stderr: str
    frames: int = 0  #: link v2 frames the firmware sent that attitude-rx answered (lockstep: each one)
    max_step_s: float = 0.0  #: the longest lockstep step: the most an answer was late, simulated s

    @property
    def lost(self) -> list[int]:
        """Samples a loss report covers (attitude-rx holds them: the last rate, no aiding)."""
        return sorted(r["first"] + i for r in self.reports if "first" in r for i in range(r["count"]))

    def delivered_once(self, n: int) -> bool:
        """Every sample 0..n-1 printed once, in order, no loss report, no duplicate."""
        losses = [r for r in self.reports if "first" in r]
        return (self.ns[:n] == list(range(n)) and self.ns == list(range(len(self.ns))) and not losses
                and self.stats.get("duplicates", 0) == 0 and self.stats.get("bad_frames", 0) == 0)


def recording(trial: Any, config: tool.Config = tool.AIDED, start: float = 0.0,
              duration: float | None = None) -> BoardRecording:
    """The trial at the firmware's sampling instants (its period), as the board's codes
    (the gyros converted ``config.gyro_oversample`` times per sample, summed)."""
    return resample(trial, config.period_s, board_channels(), start=start, duration=duration,
                    oversample=config.gyro_oversample, mean=config.gyro_mean)


def _stats(err: str) -> dict[str, int]:
    out: dict[str, int] = {}
    for ln in err.splitlines():
        if ln.startswith(("attitude-rx: link2:", "attitude-rx: samples:", "attitude-rx: reports:")):
            out.update({k: int(v) for k, v in (kv.split("=") for kv in ln.split(":", 2)[2].split())
                        if v.lstrip("-").isdigit()})
    return out


def _pad(a: np.ndarray) -> np.ndarray:
    return np.concatenate([a, np.repeat(a[-1:], PAD_SAMPLES, axis=0)])


class Relay:
    """The pty between s51 in lockstep (:class:`toolchain.firmware.Session` with
    ``lockstep=True``) and a link v2 receiver program, frame by frame.

    Between two steps of s51, :meth:`pump` passes the firmware's bytes to the pty and,
    after each complete frame, waits (in wall time) for the receiver's answer: link v2's
    receiver answers every valid frame with one ACK (docs/link.md), so one frame at a time
    gets exactly one ACK. s51 runs one step ahead (``run_lockstep(..., ahead=True)``) and
    waits for the next step's command, which goes out only when the pump has returned, so
    an ACK reaches the firmware within two steps of the end of its frame: at most
    :data:`toolchain.firmware.LOCKSTEP_BOUND_S` of simulated time, however late the
    receiver is in wall time (a loaded machine, qemu-arm). ``late=(at, seconds)`` makes the
    host late on purpose: from simulated time ``at`` for ``seconds``, the receiver's
    answers are held back (it still gets every frame), as a host stalled that long would.
    """

    def __init__(self, sess: tool.Session, late: tuple[float, float] | None = None) -> None:
        self.sess, self.late = sess, late
        self.master, self._slave = os.openpty()
        tty.setraw(self._slave)  # raw and no echo, as socat's pty,raw,echo=0
        self.port = os.ttyname(self._slave)
        self.frames = self.answers = 0  #: complete frames passed to the receiver; its ACKs
        self._a, self._b = bytearray(), bytearray()  # each side's bytes since its last delimiter
        self._held = bytearray()  # the receiver's bytes not yet written to s51's UART
        self.proc: subprocess.Popen[bytes] | None = None  #: the receiver (its exit ends a wait)
        self.deadline = time.monotonic() + sess.timeout

    def close(self) -> None:
        os.close(self.master)
        os.close(self._slave)

    def _late(self) -> bool:
        return self.late is not None and self.late[0] <= self.sess.sim_seconds < sum(self.late)

    def pump(self) -> None:
        late, start = self._late(), 0
        data = self.sess.read()
        for i, b in enumerate(data):
            if b != v2.DELIM:
                self._a.append(b)
            elif self._a:
                frame, self._a = bytes(self._a), bytearray()
                if _valid(frame, ack=False):
                    os.write(self.master, data[start:i + 1])
                    start, self.frames = i + 1, self.frames + 1
                    if not late:
                        self._wait()
        if start < len(data):
            os.write(self.master, data[start:])
        self._read(0.0)
        if not late:
            self.sess.write(bytes(self._held))
            self._held.clear()

    def _wait(self) -> None:
        """Until the receiver has answered every frame (a bound only for a broken receiver)."""
        while self.answers < self.frames:
            if time.monotonic() > self.deadline or (self.proc is not None and self.proc.poll() is not None):
                raise tool.SimTimeout(f"the receiver answered {self.answers} of {self.frames} link v2 frames "
                                      f"(at {self.sess.sim_seconds:.3f} s simulated)")
            self._read(1.0)

    def _read(self, wait: float) -> None:
        if not select.select([self.master], [], [], wait)[0]:
            return
        got = os.read(self.master, 4096)
        self._held += got
        for b in got:
            if b != v2.DELIM:
                self._b.append(b)
            elif self._b:
                self.answers += _valid(bytes(self._b), ack=True)
                self._b.clear()


def _valid(enc: bytes, *, ack: bool) -> bool:
    """An rCOBS-encoded link v2 frame with a good CRC: an ACK (``ack``) or one of A's."""
    f = v2.rcobs_decode(enc)
    return (f is not None and len(f) >= 6 and (f[0] & 0xC0 == v2.T_ACK) == ack
            and v2.crc32c(f[:-4]) == int.from_bytes(f[-4:], "big"))


def chain_image(rec: BoardRecording, build_dir: Path, config: tool.Config = tool.AIDED) -> tool.Image:
    """The data-driven sim image that serves ``rec`` (stops after its records are acknowledged)."""
    return tool.build(build_dir, config, kind="sim", sim_samples=tool.data_records(config, rec.n), data=True,
                      name="fw_chain")


def run_chain(rec: BoardRecording, rx_cmd: Sequence[str], build_dir: Path, *,
              config: tool.Config = tool.AIDED, timeout: float | None = None,
              late: tuple[float, float] | None = None, image: tool.Image | None = None) -> ChainRun:
    """The recording through firmware (s51, in lockstep with the receiver: :class:`Relay`),
    link v2, pty and attitude-rx (``rx_cmd``). ``late``: see :class:`Relay`. ``image``: the
    firmware image :func:`chain_image` built (default: built here)."""
    n = rec.n
    img = image or chain_image(rec, build_dir, config)
    timeout = timeout if timeout is not None else 40.0 * n * config.period_s + 120.0
    with tempfile.TemporaryDirectory(prefix="chain_") as tmp:
        data, conf = Path(tmp) / "codes.bin", Path(tmp) / "rx.conf"
        if (rec.oversample, rec.mean) != (config.gyro_oversample, config.gyro_mean) or rec.gyro_conversions is None:
            raise ValueError(f"the recording's gyros are converted {rec.oversample} times per sample (mean: "
                             f"{rec.mean}), the firmware's {config.gyro_oversample} ({config.gyro_mean}): make it "
                             "with recording(trial, config)")
        tool.data_file(data, config, _pad(rec.gyro_conversions),
                       *(_pad(rec.codes[k]) for k in ("acc", "mag")))
        conf.write_text(rx_config(rec.channels))
        with tool.Session(img, timeout=timeout, data=data, lockstep=True) as sess:
            relay = Relay(sess, late)
            relay.proc = proc = subprocess.Popen(
                [*rx_cmd, "--port", relay.port, "--format", "jsonl", "--estimator", "auto", "--config", str(conf),
                 "--queue", "4096"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
            try:
                fw, lines, err = _serve(sess, relay, proc, n)
            finally:
                if proc.poll() is None:
                    proc.kill()
                    proc.wait()
                relay.close()
    recs = [json.loads(x) for x in lines]
    ups = [r for r in recs if "q" in r]
    if len(ups) < n:
        raise tool.FirmwareError(f"attitude-rx printed {len(ups)} of {n} samples; stderr:\n{err}")
    return ChainRun(q=np.array([r["q"] for r in ups[:n]]), ns=[r["n"] for r in ups],
                    reports=[r for r in recs if "report" in r], stats=_stats(err), firmware=fw.stats,
                    sim_seconds=fw.sim_seconds, wall_seconds=fw.wall_seconds, stderr=err,
                    frames=relay.frames, max_step_s=sess.max_step_s)


def _serve(sess: tool.Session, relay: Relay, proc: subprocess.Popen[bytes],
           n: int) -> tuple[tool.SimOutput, list[str], str]:
    """Run the firmware until it saw every record of the n samples acknowledged; then wait
    for attitude-rx's line of sample n-1 (acknowledged records are all printed), stop it."""
    assert proc.stdout is not None and proc.stderr is not None
    banner = proc.stderr.readline().decode()  # printed once the port is configured: BOOT finds a listener
    lines: list[str] = []
    last = threading.Event()

    def read() -> None:
        assert proc.stdout is not None
        for raw in proc.stdout:
            lines.append(raw.decode())
            if f'"n":{n - 1},' in raw.decode().replace(" ", ""):
                last.set()
        last.set()  # attitude-rx ended

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    fw = sess.run_lockstep(relay.pump, describe=lambda: f"attitude-rx printed {len(lines)} lines, "
                           f"answered {relay.answers} of {relay.frames} frames", ahead=True)
    last.wait(timeout=60)  # bound only for a broken attitude-rx: acknowledged records are printed
    proc.send_signal(signal.SIGINT)
    err = banner + proc.stderr.read().decode()
    proc.wait(timeout=60)
    reader.join(timeout=60)
    if proc.returncode != 0:
        raise tool.FirmwareError(f"attitude-rx exited with {proc.returncode}:\n{err}")
    return fw, lines, err


def direct(rec: BoardRecording, config: tool.Config = tool.AIDED, *, quantized: bool = True,
           settings: dict[str, Any] | None = None, lost: Sequence[int] = ()) -> np.ndarray:
    """The library's filter (attitude_c's att_ahrs in double), one update per sample with the
    accelerometer and magnetometer only where the board sends them (NULL elsewhere), on the
    codes converted as attitude-rx converts them (``quantized``: an oversampled recording's
    gyro sums divided by its n, as the OVERSAMPLE report makes attitude-rx divide) or on the
    SI values. The ``lost`` samples are held as attitude-rx holds them: the last good rate,
    no aiding."""
    from attitude_c import _settings
    from attitude_c._lib import ffi_lib
    from attitude_c.ahrs_filter import _SPEC

    src = {k: values(rec.codes[k], rec.channels[k]) if quantized else rec.si[k] for k in ("acc", "mag")}
    src["gyro"] = values(rec.codes["gyro"], rec.channels["gyro"], rec.stream_n) if quantized else rec.si["gyro"]
    ffi, lib = ffi_lib("f64")
    s = ffi.new("att_ahrs *")
    if lib.att_ahrs_init(s, _settings.fill(ffi, lib, _SPEC, settings or {}), ffi.NULL) != 0:
        raise ValueError(f"settings: att_ahrs_init refused {settings!r}")
    q, qo = np.empty((rec.n, 4)), ffi.new("att_real[4]")
    every = {"acc": config.acc_every, "mag": config.mag_every}
    held, gyro = set(lost), list(src["gyro"][0])
    for k in range(rec.n):
        vec = [ffi.new("att_real[3]", list(src[c][k])) if every[c] and k % every[c] == 0 and k not in held
               else ffi.NULL for c in ("acc", "mag")]
        gyro = gyro if k in held else list(src["gyro"][k])
        st = lib.att_ahrs_update(s, gyro, vec[0], vec[1], config.period_s, qo)
        if st != 0:
            raise RuntimeError(f"att_ahrs_update failed at sample {k} (status {st})")
        q[k] = list(qo)
    return q
