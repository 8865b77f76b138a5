"""``--firmware s51``: the acquisition side as the real AT89S51 firmware in s51.

The firmware's simulation image (firmware/, built by ``firmware.tool``) runs
the unchanged firmware — TLC2543 driver, Timer 0 sampling loop, link sender,
block encoder — in ``s51 -t C51`` against a TLC2543 + gyro model compiled
into the image, with its UART on a pty pair whose other end is the C link
receiver. That model's three analog inputs are sinusoids defined by integer
parameters (``firmware.tool.Gyro``: input = (offset + 32767 sin(2π(phase +
k·step)/256) / 2^shift) / 65536 · Vref for sample k), so with this option the
motion is *the firmware's*, mapped to rad/s by the host's rad/s per code.

The gyro parameters are chosen so that the motion has a closed-form truth
(:class:`FirmwareTrajectory`): X and Y a quadrature pair of equal amplitude
A (X = A cos β, Y = A sin β, β advancing at Ω), Z a constant rate c. The body
rate ω(t) = R_z(β(t))·[A, 0, c] turns about the body z axis at Ω, and in a
frame turning with it the rate is constant, so

    Q(t) = q_z(β₀) ⊗ q(u t) ⊗ q_z(−β(t)),   u = [A, 0, c + Ω],

exactly (q_z(a): rotation by a about z; q(v): rotation vector v; Q(0) = 1).
Check: with S(t) = exp(t[u×]) R_z(−Ωt), Sᵀ Ṡ = [(R_z(Ωt) u − Ω e_z)×] =
[(R_z(Ωt)[A, 0, c])×]; the constant factors R_z(±β₀) turn that into
R_z(β(t))[A, 0, c]. Classical coning is the case c = −Ω(1 − cos α),
A = Ω sin α; here A, c and Ω are whatever the integers give. The truth never
goes through an integrator (tests/test_sim_truth.py checks it against RK4).

Sample k is taken at the midpoint of period k (the rate function's time
origin is placed so), one conversion per axis per period (the firmware does
no oversampling), and the in-image model truncates (code = v >> 4): the host
uses the zero code 2047.5 of a truncating converter.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..errors import InvalidArgument
from ._rot import quat_mul, rotvec_to_quat
from .trajectory import Trajectory

__all__ = ["FW_GYROS", "FirmwareTrajectory", "firmware_available", "run_firmware"]

TICK_HZ = 11_059_200 // 12 // 256  # the firmware's Timer 0 ticks per second (3600)

# (offset, shift, phase, step) per axis. X, Y: a quadrature pair (phase of X =
# phase of Y + 64, a quarter turn) about mid-scale, ±512 LSB (shift 2), 4 cycles
# per 256 samples (0.20 Hz at h = 0.08 s); Z: a constant −95.5 LSB (offset
# 31240 = 32768 − 1528: the middle of a code, so truncation loses nothing).
FW_GYROS = ((32768, 2, 64, 4), (32768, 2, 0, 4), (31240, 0, 0, 0))


def _tool() -> Any:
    root = Path(__file__).resolve().parents[2]
    if not (root / "firmware" / "tool.py").exists():
        raise ImportError("--firmware s51 needs a source checkout (firmware/tool.py next to "
                          "attitude_c/)")
    if str(root) not in sys.path:
        sys.path.insert(0, str(root))
    from firmware import tool  # type: ignore[import-not-found]

    return tool


def firmware_available() -> bool:
    try:
        _tool()
    except ImportError:
        return False
    import shutil

    return all(shutil.which(t) for t in ("sdcc", "s51", "socat"))


def _qz(angle: np.ndarray) -> np.ndarray:
    a = np.asarray(angle, dtype=float)
    q = np.zeros(a.shape + (4,))
    q[..., 0] = np.cos(a / 2)
    q[..., 3] = np.sin(a / 2)
    return q


@dataclass
class FirmwareTrajectory(Trajectory):
    """Body rates of the firmware's gyro model, with the closed-form truth (module doc)."""

    period: float = 0.08
    rad_per_s_per_code: float = 1e-3
    gyros: tuple[tuple[int, int, int, int], ...] = FW_GYROS
    duration: float = 60.0

    def __post_init__(self) -> None:
        self.name = "firmware"
        if len(self.gyros) != 3 or any(len(g) != 4 for g in self.gyros):
            raise InvalidArgument("gyros needs 3 (offset, shift, phase, step) tuples")
        if not (self.period > 0 and math.isfinite(self.period)):
            raise InvalidArgument(f"period must be > 0 s, got {self.period!r}")
        (ox, shx, phx, stx), (oy, shy, phy, sty), (oz, shz, phz, stz) = self.gyros
        if not (ox == oy == 32768 and shx == shy and stx == sty and (phx - phy) % 256 == 64 and stz == 0):
            raise InvalidArgument(
                "gyros must be X, Y a quadrature pair about mid-scale (offset 32768, same shift and "
                "step, phase of X = phase of Y + 64) and Z constant (step 0): the motion with a "
                f"closed-form truth; got {self.gyros}")
        k = self.rad_per_s_per_code
        # rate (rad/s) = k · 4096 · (fraction − 1/2), fraction of the model above
        self._amp = k * 4096 * 32767 / 2**shy / 65536
        self._c = k * 4096 * ((oz + 32767 * math.sin(2 * math.pi * phz / 256) / 2**shz) / 65536 - 0.5)
        self._w = 2 * math.pi * sty / (256 * self.period)  # Ω, rad/s
        self._b0 = 2 * math.pi * phy / 256 - self._w * self.period / 2  # β(0): sample k at (k + ½) h
        self._u = np.array([self._amp, 0.0, self._c + self._w])

    def _beta(self, t: Any) -> np.ndarray:
        return self._b0 + self._w * np.asarray(t, dtype=float)

    def omega(self, t: Any) -> np.ndarray:
        b = self._beta(t)
        return np.stack([self._amp * np.cos(b), self._amp * np.sin(b), np.full_like(b, self._c)], axis=-1)

    def increments(self, t0: float, h: float, n: int) -> np.ndarray:
        t = t0 + np.arange(n + 1) * h
        b = self._beta(t)
        if self._w == 0:
            xy = [self._amp * np.cos(b[:-1]) * h, self._amp * np.sin(b[:-1]) * h]
        else:
            xy = [self._amp / self._w * np.diff(np.sin(b)), -self._amp / self._w * np.diff(np.cos(b))]
        return np.stack([*xy, np.full(n, self._c * h)], axis=-1)

    def quat(self, t: Any) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        turn = rotvec_to_quat(t[..., None] * self._u)
        return quat_mul(quat_mul(_qz(np.full_like(t, self._b0)), turn), _qz(-self._beta(t)))

    def params(self) -> dict[str, Any]:
        return {"trajectory": self.name, "gyros_offset_shift_phase_step": [list(g) for g in self.gyros],
                "rate_amplitude_xy_dps": math.degrees(self._amp), "rate_z_dps": math.degrees(self._c),
                "frequency_hz": self._w / (2 * math.pi),
                "truth": "closed form: q_z(β0) ⊗ q(u t) ⊗ q_z(−β(t))"}


def run_firmware(n: int, period: float, traj: FirmwareTrajectory, attempts: int,
                 progress: Callable[[str, int, int], None] | None = None
                 ) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """Build and run the firmware's simulation image for n samples.

    Returns (codes (m, 3), sample index (m,), statistics)."""
    tool = _tool()
    ticks = period * TICK_HZ
    if abs(ticks - round(ticks)) > 1e-6 or not 1 <= round(ticks) <= 32767:
        raise InvalidArgument(f"--firmware s51 needs a period that is a whole number of the "
                              f"firmware's 1/{TICK_HZ} s ticks, got {period} s")
    from ..errors import DeviceError

    try:
        # Link timeouts of 1 s of simulated time (the chip's default is 50 ms): s51 runs in
        # simulated time, the host end in wall time, and a host answering late on a loaded
        # machine must not make the firmware resend a block the host already accepted (the
        # protocol's duplicate, docs/link.md), which would shift the numbering of the samples
        # after it; late answers cost overruns instead, reported in place and counted as lost.
        cfg = tool.Config(period_ticks=round(ticks), max_attempts=attempts, syn_timeout=3600,
                          answer_timeout=3600)
        gyros = [tool.Gyro(*g) for g in traj.gyros]
        img = tool.build(tool.BUILD / "sim", cfg, kind="sim", sim_blocks=n + 1, gyros=gyros,
                         name="fw_sim_attitude")
        if progress is not None:
            progress("s51", 0, n)
        res = tool.run(img, timeout=max(60.0, 3.0 * n * period + 30.0))
        stream = res.stream  # the library's block decoder and sequence tracker
    except (tool.FirmwareError, OSError, ValueError) as exc:
        raise DeviceError(f"firmware run in s51 failed: {exc}") from exc
    if progress is not None:
        progress("s51", n, n)
    got = {s.seq: s.codes for s in stream if isinstance(s, tool.Sample) and s.seq < n}
    reports = [r.kind for r in stream if not isinstance(r, tool.Sample)]
    # attitude-rx's policy for samples the stream reports lost (docs/cross-build.md): hold
    # the last good sample over them; before the first good sample there is nothing to hold
    rows: list[tuple[int, int, int]] = []
    idx_l: list[int] = []
    held: list[int] = []
    last: tuple[int, int, int] | None = None
    for k in range(max(got, default=-1) + 1):
        if k in got:
            last = got[k]
        elif last is None:
            continue
        else:
            held.append(k)
        rows.append(last)
        idx_l.append(k)
    codes = np.array(rows, dtype=np.int64).reshape(-1, 3)
    idx = np.array(idx_l, dtype=np.int64)
    stats = {"link": "firmware (s51) → pty → C receiver", "backend": "s51 firmware",
             "ber": 0.0, "sent": int(res.stats.get("sent", 0)), "delivered": len(got),
             "delivered_ok": len(got), "duplicated": 0, "corrupted_undetected": 0,
             "lost": n - len(got), "held": held, "reports": reports,
             "firmware_stats": dict(res.stats), "receiver": dict(res.host.stats()),
             "max_stack_pointer": res.max_sp, "simulated_s": res.sim_seconds,
             "wall_s": res.wall_seconds, "flash_bytes": img.flash}
    return codes, idx, stats
