"""``--firmware s51``: the acquisition side as the real AT89S51 firmware in s51.

The firmware's simulation image (firmware/, built by ``firmware.tool``) runs
the unchanged firmware — TLC2543 driver, Timer 0 sampling loop, link sender —
in ``s51 -t C51`` against a TLC2543 + gyro model compiled into the image,
with its UART on a pty pair whose other end is the C link receiver. That
model's three analog inputs are sinusoids defined by integer parameters
(``firmware.tool.Gyro``: input = (offset + 32767 sin(2π(phase + k·step)/256)
/ 2^shift) / 65536 · Vref for sample k), so with this option the motion is
*the firmware's*: body rates that are sinusoids at the sampling instants,
mapped to rad/s through the simulator's gyro and conditioning model. The
truth is the exact integral of those rates (closed-form increments over
1/64 of a period, integrated with rv3: error < 1e-12 rad).

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
SUB = 64  # truth sub-steps per period

# (offset, shift, phase, step) per axis: zero mean (offset = mid-scale),
# ±512 LSB (shift 2), 4, 5 and 6 cycles per 256 samples (0.20, 0.24, 0.29 Hz
# at h = 0.08 s), phases a quarter and a half turn apart.
FW_GYROS = ((32768, 2, 0, 4), (32768, 2, 64, 5), (32768, 2, 128, 6))


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


@dataclass
class FirmwareTrajectory(Trajectory):
    """Body rates of the firmware's gyro model, with the exact truth."""

    period: float = 0.08
    rad_per_s_per_code: float = 1e-3
    gyros: tuple[tuple[int, int, int, int], ...] = FW_GYROS
    duration: float = 60.0

    def __post_init__(self) -> None:
        self.name = "firmware"
        if len(self.gyros) != 3:
            raise InvalidArgument("gyros needs 3 (offset, shift, phase, step) tuples")
        g = np.asarray(self.gyros, dtype=float)
        self._off, self._sh, self._ph, self._st = g[:, 0], g[:, 1], g[:, 2], g[:, 3]
        # rate (rad/s) = k · 4096 · (fraction − 1/2); fraction of the model above
        self._amp = self.rad_per_s_per_code * 4096 * 32767 / 2**self._sh / 65536
        self._bias = self.rad_per_s_per_code * 4096 * (self._off / 65536 - 0.5)
        self._w = 2 * math.pi * self._st / (256 * self.period)  # rad/s of the sine
        self._a0 = 2 * math.pi * self._ph / 256 - self._w * self.period / 2  # sample k at (k+½)h
        n = math.ceil(self.duration / self.period) + 2
        hs = self.period / SUB
        import attitude_c

        inc = self.increments(0.0, hs, n * SUB)
        q = attitude_c.integrate(inc, method="rv3", q0=np.array([1.0, 0, 0, 0]))
        self._grid_h = 3 * hs
        self._grid = np.vstack([[1.0, 0, 0, 0], q])

    def omega(self, t: Any) -> np.ndarray:
        t = np.asarray(t, dtype=float)[..., None]
        return self._bias + self._amp * np.sin(self._a0 + self._w * t)

    def increments(self, t0: float, h: float, n: int) -> np.ndarray:
        t = t0 + np.arange(n + 1)[:, None] * h
        prim = self._bias * t - self._amp / self._w * np.cos(self._a0 + self._w * t)
        return np.diff(prim, axis=0)

    def quat(self, t: Any) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        i = np.clip(np.floor(t / self._grid_h + 1e-9).astype(int), 0, len(self._grid) - 1)
        t_i = i * self._grid_h
        dt = t - t_i
        # the rest of the way (< 3/64 period) as one rotation vector: exact to O(dt³)
        mid = t_i + dt / 2
        rv = self.omega(mid) * dt[..., None]
        return quat_mul(self._grid[i], rotvec_to_quat(rv))

    def params(self) -> dict[str, Any]:
        return {"trajectory": self.name, "gyros_offset_shift_phase_step": [list(g) for g in self.gyros],
                "rate_amplitude_dps": np.degrees(self._amp).tolist(),
                "rate_bias_dps": np.degrees(self._bias).tolist(),
                "frequency_hz": (self._w / (2 * math.pi)).tolist()}


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
        cfg = tool.Config(period_ticks=round(ticks), max_attempts=attempts)
        gyros = [tool.Gyro(*g) for g in traj.gyros]
        img = tool.build(tool.BUILD / "sim", cfg, kind="sim", sim_blocks=n + 1, gyros=gyros,
                         name="fw_sim_attitude")
        if progress is not None:
            progress("s51", 0, n)
        res = tool.run(img, timeout=max(60.0, 3.0 * n * period + 30.0))
    except (tool.FirmwareError, OSError, ValueError) as exc:
        raise DeviceError(f"firmware run in s51 failed: {exc}") from exc
    if progress is not None:
        progress("s51", n, n)
    samples = [s for s in res.stream if isinstance(s, tool.Sample)]
    reports = [r.kind for r in res.stream if not isinstance(r, tool.Sample)]
    codes = np.array([s.codes for s in samples], dtype=np.int64).reshape(-1, 3)
    idx = np.array([s.seq for s in samples], dtype=np.int64)
    keep = idx < n
    stats = {"link": "firmware (s51) → pty → C receiver", "backend": "s51 firmware",
             "ber": 0.0, "sent": int(res.stats.get("sent", 0)), "delivered": int(keep.sum()),
             "delivered_ok": int(keep.sum()), "duplicated": 0, "corrupted_undetected": 0,
             "lost": int(n - len(np.unique(idx[keep]))), "reports": reports,
             "firmware_stats": dict(res.stats), "receiver": dict(res.host.stats()),
             "max_stack_pointer": res.max_sp, "simulated_s": res.sim_seconds,
             "wall_s": res.wall_seconds, "flash_bytes": img.flash}
    return codes[keep], idx[keep], stats
