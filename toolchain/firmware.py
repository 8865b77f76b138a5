"""The AT89S51 firmware in the tooling layer: build it with SDCC, run it in s51
against the host end of the link, and plug it into the simulator as an
acquisition source (docs/firmware.md, docs/architecture.md).

Three kinds of image come from the same sources (firmware/main.c + the
library's csrc/src/tlc2543.c, csrc/src/link_sender.c and csrc/src/block.c,
unchanged):

* ``production`` — what goes into the chip: TLC2543 on P1.0-P1.4.
* ``sim`` — the same firmware, but the driver's pin HAL calls a TLC2543 +
  gyro device model compiled into the image (firmware/sim/tlc_model.c), and
  the program stops itself through the uCsim simulator interface after a
  given number of accepted blocks (or sample records), printing its link
  statistics (main.c's hooks, firmware/hooks.h and firmware/sim/hooks.h).
* ``bench`` — production pins plus machine-cycle counters (Timer 0 based).

Running: s51 (``-t C51``, 128 B RAM) gets its UART on one end of a
``socat pty,raw,echo=0`` pair; :class:`LinkHost` (the C receiver B of
libattitude through CFFI, or the Python one) answers on the other end,
optionally injecting faults (NAKs, silence after 0xAA). The blocks are
decoded and numbered by the library (:mod:`attitude_c.link.block`).

    img = build(BUILD / "fw", Config(), kind="sim", sim_blocks=50)
    res = run(img, LinkHost())
    stream = decode_stream(res.host.blocks)

The simulator's source: importing this module registers ``"s51"``
(:func:`attitude_c.sim.register_source`), so ``SimConfig(firmware="s51",
trajectory=FirmwareTrajectory(...))`` runs the firmware; ``python -m
toolchain.simulate --firmware s51 ...`` is ``attitude simulate`` with it.
The runtime package never imports this module.
"""

from __future__ import annotations

import math
import os
import re
import select
import shutil
import signal
import subprocess
import tempfile
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Literal

import numpy as np

from attitude_c.errors import BlockFormatError, DeviceError, InvalidArgument
from attitude_c.link import block
from attitude_c.reference import quat_multiply, rotvec_to_quat
from attitude_c.sim import (
    Conditioning,
    GyroModel,
    SimConfig,
    Source,
    SourceOutput,
    Trajectory,
    register_source,
)
from attitude_c.sim.host import Calibration
from attitude_c.sim.link import Delivered
from attitude_c.sim.sensors import DEG

from . import targets

ROOT = Path(__file__).resolve().parents[1]
FW_DIR = ROOT / "firmware"
CSRC = ROOT / "csrc"
TOOLCHAIN = ROOT / "toolchain"
BUILD = ROOT / "build" / "firmware"

XTAL_HZ = 11_059_200
MACHINE_HZ = XTAL_HZ // 12          #: machine cycles per second (12-clock core)
TICK_HZ = MACHINE_HZ // 256         #: Timer 0 ticks per second (3600)
FLASH_SIZE = 4096
IRAM_SIZE = 128
#: The aided board's AT89S52 (toolchain/mcs52.toml): 8 KB of flash, 256 bytes of RAM.
FLASH_SIZE_52 = 8192
IRAM_SIZE_52 = 256
#: Link block size N the firmware sends: one record of the block format (attitude/block.h).
BLOCK_SIZE = block.fmt().size
#: UART rates Timer 1 in mode 2 makes exactly from 11.0592 MHz (SMOD 0 or 1).
BAUD_RATES = (1200, 2400, 4800, 9600, 14400, 19200, 28800, 57600)
#: ... and Timer 2 (the aided AT89S52): XTAL / (32 (65536 - RCAP2)), up to BOOT's 255 x 1200.
BAUD_RATES_T2 = tuple(b for b in range(1200, 255 * 1200 + 1, 1200) if (XTAL_HZ // 32) % b == 0)
#: Board types of the firmware (Config.board): the block format's CHANNELS names.
BOARDS = ("gyro3", "aided9")
#: Bytes on the wire per delivered block: 0xAA, 0xBB, N data, checksum, answer.
WIRE_BYTES_PER_BLOCK = 1 + 1 + BLOCK_SIZE + 1 + 1

#: Scheduling priority of s51 under the host end (see Session.run).
S51_NICE = 10
#: Instructions s51 runs per console ``step`` in lockstep (Session.run_lockstep). An 8051
#: instruction takes at most 4 machine cycles (MUL, DIV), so a step lasts at most
#: 4 * LOCKSTEP_INSNS machine cycles = 43.4 ms of simulated time (about 16 ms with the
#: firmware's instruction mix): the most simulated time by which a host answer can reach
#: the firmware late, below the chip's 50 ms link timeouts (Config's default).
LOCKSTEP_INSNS = 10_000
#: The hard bound above, in simulated seconds.
LOCKSTEP_BOUND_S = 4 * LOCKSTEP_INSNS / MACHINE_HZ
#: Steps of ``run_lockstep(..., ahead=True)`` (the aided chain): half as long, since an
#: answer can be one step later there; the same bound, LOCKSTEP_BOUND_S.
LOCKSTEP_AHEAD_INSNS = LOCKSTEP_INSNS // 2

SOURCES = [FW_DIR / "main.c", FW_DIR / "link_state.c", CSRC / "src" / "tlc2543.c", CSRC / "src" / "link_sender.c",
           CSRC / "src" / "block.c"]
#: The link v2 build: link2_sender.c (single instance) instead of link_sender.c.
SOURCES_V2 = [CSRC / "src" / "link2_sender.c" if s.name == "link_sender.c" else s for s in SOURCES]
#: The aided board (link v2 only): the CHANNELS report's encoder too.
SOURCES_AIDED = [*SOURCES_V2, CSRC / "src" / "block_channels.c"]
#: ... with gyro oversampling: the OVERSAMPLE report's and the sums' encoders.
SOURCES_SUMS = [CSRC / "src" / "block_sums.c"]
#: Gyro conversions per sample the aided board can sum (FW_GYRO_OVERSAMPLE: a power of two,
#: so the accelerometer's and magnetometer's codes times n are a shift; 8 x 4095 fits a word).
GYRO_OVERSAMPLE = (1, 2, 4, 8)
#: Link protocols of the firmware (Config.link).
LINKS = ("legacy", "v2")
SIM_HAL_HEADER = FW_DIR / "sim" / "tlc_hal_sim.h"


class FirmwareError(RuntimeError):
    """Build or simulation failure (message says what and where)."""


class FirmwareTooBig(FirmwareError):
    """The image does not fit the AT89S51 (4 KB flash, 128 B RAM)."""


class SimTimeout(FirmwareError, TimeoutError):
    """The simulation did not stop by itself within the wall-clock limit."""


# -- configuration --------------------------------------------------------

@dataclass(frozen=True)
class Config:
    """Build-time settings (firmware/config.h). Times are Timer 0 ticks (1/3600 s)."""

    baud: int = 9600
    period_ticks: int = 72            #: 20 ms: 50 samples/s
    syn_timeout: int = 180            #: 50 ms
    answer_timeout: int = 180         #: 50 ms
    max_attempts: int = 5
    selftest_retry: int = 3600        #: 1 s
    link: Literal["legacy", "v2"] = "legacy"  #: link protocol (firmware/config.h FW_LINK_V2)
    v2_rto: int = 720                 #: v2: ticks without progress before a go-back / probe (200 ms)
    v2_samples: int = 4               #: v2: samples per DATA frame (1..24)
    v2_ring: int = 4                  #: v2: records the sender keeps until acknowledged (power of two)
    v2_batch: int = 0                 #: v2, aided: records a DATA frame waits for (0: none; ATT_LINK2_ONE_BATCH)
    v2_hold: int = 0                  #: v2, aided: ... for at most this many ticks (ATT_LINK2_ONE_HOLD)
    board: Literal["gyro3", "aided9"] = "gyro3"  #: the AT89S51 gyro board or the aided AT89S52 (FW_AIDED)
    acc_every: int = 1                #: aided: accelerometer record every acc_every samples (0: none)
    mag_every: int = 1                #: aided: magnetometer record every mag_every samples (0: none)
    mag_sr: bool = False              #: aided: magnetometer set/reset on P3.4 (FW_MAG_SR; docs/firmware.md)
    gyro_oversample: int = 1          #: aided: gyro conversions summed per sample (FW_GYRO_OVERSAMPLE: 1, 2, 4, 8)
    gyro_mean: bool = False           #: aided, oversampled: send the rounded mean code, not the sum (FW_GYRO_MEAN)

    def __post_init__(self) -> None:
        if self.board not in BOARDS:
            raise ValueError(f"board must be one of {BOARDS}, got {self.board!r}")
        rates = BAUD_RATES_T2 if self.aided else BAUD_RATES
        if self.baud not in rates:
            raise ValueError(f"baud must be one of {rates} (exact with an 11.0592 MHz crystal, "
                             f"{'Timer 2' if self.aided else 'Timer 1'}), got {self.baud}")
        if self.aided:
            if self.link != "v2":
                raise ValueError(f"the aided board speaks link v2 only, got link={self.link!r}")
            for name in ("acc_every", "mag_every"):
                v = getattr(self, name)
                if v not in (0, 1, 2, 4, 8, 16, 32, 64, 128):
                    raise ValueError(f"{name} must be 0 (not sent) or a power of two 1..128, got {v}")
        for name in ("period_ticks", "syn_timeout", "answer_timeout", "selftest_retry"):
            v = getattr(self, name)
            if not 1 <= v <= 32767:
                raise ValueError(f"{name} must be 1..32767 ticks, got {v}")
        if self.link not in LINKS:
            raise ValueError(f"link must be one of {LINKS}, got {self.link!r}")
        if not 1 <= self.v2_rto <= 32767:
            raise ValueError(f"v2_rto must be 1..32767 ticks, got {self.v2_rto}")
        if not 1 <= self.v2_samples <= 24:
            raise ValueError(f"v2_samples must be 1..24, got {self.v2_samples}")
        if self.v2_ring not in (1, 2, 4, 8, 16, 32, 64):
            raise ValueError(f"v2_ring must be a power of two 1..64, got {self.v2_ring}")
        if not 0 <= self.v2_batch <= self.v2_ring:
            raise ValueError(f"v2_batch must be 0..v2_ring ({self.v2_ring}), got {self.v2_batch}")
        if not 0 <= self.v2_hold <= 32767:
            raise ValueError(f"v2_hold must be 0..32767 ticks, got {self.v2_hold}")
        if self.mag_sr and not (self.aided and self.mag_every):
            raise ValueError("mag_sr needs the aided board with its magnetometer (board='aided9', mag_every > 0)")
        if self.gyro_oversample not in GYRO_OVERSAMPLE:
            raise ValueError(f"gyro_oversample must be one of {GYRO_OVERSAMPLE}, got {self.gyro_oversample}")
        if self.gyro_oversample > 1 and not (self.aided and self.period_ticks % self.gyro_oversample == 0):
            raise ValueError(f"gyro_oversample {self.gyro_oversample} needs the aided board (board='aided9') and "
                             f"period_ticks a multiple of it, got board={self.board!r}, period_ticks={self.period_ticks}")
        if self.gyro_mean and self.gyro_oversample == 1:
            raise ValueError("gyro_mean needs gyro_oversample > 1")
        if (self.v2_batch or self.v2_hold) and not self.aided:
            raise ValueError("v2_batch and v2_hold are the aided board's (board='aided9')")
        if not 1 <= self.max_attempts <= 255:
            raise ValueError(f"max_attempts must be 1..255, got {self.max_attempts}")

    @property
    def aided(self) -> bool:
        return self.board == "aided9"

    @property
    def period_s(self) -> float:
        return self.period_ticks / TICK_HZ

    @property
    def target(self) -> str:
        """The toolchain target (toolchain/*.toml): the AT89S51 or the aided AT89S52."""
        return "mcs52" if self.aided else "mcs51"

    @property
    def flash_size(self) -> int:
        return FLASH_SIZE_52 if self.aided else FLASH_SIZE

    @property
    def iram_size(self) -> int:
        return IRAM_SIZE_52 if self.aided else IRAM_SIZE

    def defines(self) -> list[str]:
        return [f"FW_BAUD={self.baud}L", f"FW_PERIOD_TICKS={self.period_ticks}",
                f"FW_SYN_TIMEOUT_TICKS={self.syn_timeout}",
                f"FW_ANSWER_TIMEOUT_TICKS={self.answer_timeout}",
                f"FW_MAX_ATTEMPTS={self.max_attempts}",
                f"FW_SELFTEST_RETRY_TICKS={self.selftest_retry}",
                *([] if self.link == "legacy" else
                  ["FW_LINK_V2=1", "ATT_LINK2_ONE=1", f"ATT_LINK2_ONE_RTO={self.v2_rto}",
                   f"ATT_LINK2_ONE_SAMPLES={self.v2_samples}", f"ATT_LINK2_ONE_RING={self.v2_ring}"]),
                *([] if self.link == "legacy" or self.aided else
                  ["ATT_LINK2_CURSOR=0"]),  # the AT89S51 v2 image as it was (attitude/link2.h)
                *([] if not self.aided else
                  ["FW_AIDED=1", f"FW_ACC_EVERY={self.acc_every}", f"FW_MAG_EVERY={self.mag_every}",
                   "ATT_LINK2_CRC_TABLE=1", "ATT_LINK2_ONE_RING_IDATA=1", f"ATT_LINK2_ONE_BATCH={self.v2_batch}",
                   f"ATT_LINK2_ONE_HOLD={self.v2_hold}", f"FW_MAG_SR={int(self.mag_sr)}",
                   *([f"FW_GYRO_OVERSAMPLE={self.gyro_oversample}", f"FW_GYRO_MEAN={int(self.gyro_mean)}"]
                     if self.gyro_oversample > 1 else [])])]

    @property
    def stream_n(self) -> int:
        """Conversions per sample word the stream announces (OVERSAMPLE n; 1: plain codes)."""
        return 1 if self.gyro_mean else self.gyro_oversample


#: The aided board's default build (docs/firmware.md "The aided board"): link v2 at
#: 115200 baud with a ring of 16 records in the upper RAM, frames of up to 16 samples held
#: back for 6 records or 108 ticks (30 ms), and the sampling plan chosen there
#: (bench/aided.py): gyros at 50 samples/s (20 ms), accelerometer and magnetometer in every
#: sample: about 63 % CPU in s51.
AIDED = Config(board="aided9", link="v2", baud=115200, period_ticks=72, v2_ring=16, v2_samples=16, v2_batch=6,
               v2_hold=108, acc_every=1, mag_every=1)


@dataclass(frozen=True)
class Gyro:
    """One simulated gyro channel of the device model (firmware/sim/tlc_model.c).

    Its output, as a fraction of Vref, for the k-th conversion of the channel
    (the sample taken at t = k * period) is
    ``(offset + 32767 sin(2 pi (phase + k step) / 256) / 2**shift) / 65536``.
    """

    offset: int
    shift: int
    phase: int
    step: int

    def fraction(self, k: int) -> float:
        """Analog input / Vref for sample k (exact sine, no table)."""
        s = 32767.0 * math.sin(2.0 * math.pi * ((self.phase + k * self.step) % 256) / 256.0)
        return (self.offset + s / 2.0 ** self.shift) / 65536.0

    def volts(self, k: int, vref: float = 5.0) -> float:
        return vref * self.fraction(k)

    def lsb(self, k: int) -> float:
        """The analog input of sample k in 12-bit LSB (an ideal code is its floor)."""
        return 4096.0 * self.fraction(k)


#: X, Y, Z: different offsets, amplitudes (1024, 512, 256 LSB), phases and
#: frequencies, so a swapped or shifted channel cannot match by accident.
GYROS = (Gyro(32768, 1, 0, 3), Gyro(24576, 2, 64, 5), Gyro(40960, 3, 128, 7))


#: The aided board's accelerometer X, Y, Z (AIN3-AIN5) and magnetometer X, Y, Z (AIN6-AIN8)
#: in the device model: the same form as the gyros, each with its own offset, amplitude
#: (256, 128, 256; 512, 256, 512 LSB), phase and frequency.
AUX = (Gyro(32768, 3, 32, 1), Gyro(30000, 4, 96, 2), Gyro(45000, 3, 160, 1),
       Gyro(20000, 2, 16, 2), Gyro(36000, 3, 200, 3), Gyro(28000, 2, 80, 1))


#: The device model's magnetometer bridge offset (firmware/sim/tlc_model.c FW_SIM_BRIDGE), in
#: 16-bit fractions of Vref: 256 LSB, the same in the set and the reset state; a code read
#: without set/reset carries it, the set/reset combination cancels it.
BRIDGE = 4096


def _gyro_defines(gyros: Sequence[Gyro], aux: Sequence[Gyro] = ()) -> list[str]:
    out = []
    for name, g in zip("XYZ", gyros):
        out += [f"FW_SIM_{name}_OFF={g.offset}u", f"FW_SIM_{name}_SH={g.shift}",
                f"FW_SIM_{name}_PH={g.phase}", f"FW_SIM_{name}_STEP={g.step}"]
    if aux:  # the aided model's six more inputs, as comma lists (firmware/sim/tlc_model.c)
        for field, macro in (("offset", "OFF"), ("shift", "SH"), ("phase", "PH"), ("step", "STEP")):
            out.append(f"FW_SIM_AUX_{macro}=" + ",".join(str(getattr(g, field)) for g in aux))
        out.append(f"FW_SIM_BRIDGE={BRIDGE}u")
    return out


# -- build ----------------------------------------------------------------

#: CRC-32C (Castagnoli), reflected: the polynomial 0x1EDC6F41 with its bits reversed.
CRC32C_REFLECTED = 0x82F63B78


def crc32c_table() -> list[int]:
    """The 256 remainders of the byte-at-a-time reflected CRC-32C: entry i is i shifted
    right through 8 steps of the polynomial division (link v2's CRC, docs/link.md)."""
    out = []
    for i in range(256):
        r = i
        for _ in range(8):
            r = (r >> 1) ^ (CRC32C_REFLECTED if r & 1 else 0)
        out.append(r)
    return out


def _crc_table_source(path: Path) -> Path:
    """The aided image's CRC table (ATT_LINK2_CRC_TABLE, csrc/src/link2_sender.c): four
    byte planes att_link2_crc_t0..t3 in code memory, written from :func:`crc32c_table`."""
    t = crc32c_table()
    lines = ["/* generated by toolchain/firmware.py (crc32c_table): do not edit */", "#include <stdint.h>"]
    for plane in range(4):
        vals = ", ".join(f"0x{(v >> (8 * plane)) & 0xFF:02X}" for v in t)
        lines.append(f"__code const uint8_t att_link2_crc_t{plane}[256] = {{ {vals} }};")
    path.write_text("\n".join(lines) + "\n")
    return path


@dataclass
class Image:
    """A linked firmware image and its memory use (from SDCC's .mem report)."""

    ihx: Path
    kind: str
    config: Config
    flash: int          #: bytes of code + constants
    ram_static: int     #: bytes of internal RAM below the stack (registers, variables, bits)
    stack_start: int    #: first stack byte (SP is set to stack_start - 1 at reset)
    stack_free: int     #: bytes from stack_start to the end of RAM (0x7F)

    def size_report(self) -> str:
        size, iram = self.config.flash_size, self.config.iram_size
        flash = (f"flash {self.flash} / {size} bytes ({size - self.flash} free)"
                 if self.kind == "production" else
                 f"code {self.flash} bytes ({self.kind} image: model/counters, not for the chip)")
        return (f"{self.ihx.name}: {flash}, RAM {self.ram_static} / {iram} bytes static, "
                f"stack 0x{self.stack_start:02X}..0x{iram - 1:02X} = {self.stack_free} bytes free")


def _sdcc_flags(target: str = "mcs51") -> list[str]:
    t = targets.load(target)
    t.require()
    return list(t.cflags)


def _without_code_size(flags: list[str]) -> list[str]:
    i = flags.index("--code-size")
    return flags[:i] + flags[i + 2:]


def _run(cmd: list[str]) -> None:
    proc = subprocess.run(cmd, check=False, capture_output=True, text=True)
    if proc.returncode != 0:
        raise FirmwareError(f"command failed: {' '.join(cmd)}\n{proc.stdout}{proc.stderr}")


def parse_mem(mem: Path) -> tuple[int, int, int]:
    """(flash bytes, stack start, stack bytes available) from an SDCC .mem file."""
    text = mem.read_text()
    m = re.search(r"ROM/EPROM/FLASH\s+0x[0-9a-fA-F]+\s+0x[0-9a-fA-F]+\s+(\d+)", text)
    s = re.search(r"Stack starts at: 0x([0-9a-fA-F]+) \(sp set to 0x[0-9a-fA-F]+\) with (\d+) bytes available", text)
    if not m or not s:
        raise FirmwareError(f"cannot read the memory report {mem}")
    return int(m.group(1)), int(s.group(1), 16), int(s.group(2))


def build(out_dir: Path | str = BUILD, config: Config = Config(), *, kind: str = "production",
          sim_blocks: int = 0, sim_samples: int = 0, gyros: Sequence[Gyro] = GYROS, faults: Iterable[str] = (),
          extra_defines: Iterable[str] = (), name: str | None = None,
          code_size: int | None = None, aux: Sequence[Gyro] = AUX, data: bool = False) -> Image:
    """Compile and link one image; raise :class:`FirmwareTooBig` if it does not fit.

    ``kind``: ``production``, ``sim`` (device model + simulator stop after
    ``sim_blocks`` accepted blocks or ``sim_samples`` accepted sample records, whichever
    comes first; 0 = that count never stops it) or ``bench`` (production pins,
    self-test skipped because s51's port pins read 1, cycle counters).
    ``faults`` (sim only): ``dout_stuck_high``, ``dout_stuck_low``, ``eoc_stuck`` (every
    conversion), ``adc_error_at=K`` (EOC stuck in the scan of sample K only, 0 <= K < 256: one
    ADC_ERROR report in that sample's place, then sampling goes on).
    ``config.board = "aided9"`` builds the aided AT89S52 image (toolchain/mcs52.toml: 8 KB,
    256 B; ``code_size`` defaults to the chip's flash); its device model serves ``aux`` on
    AIN3-AIN8 (accelerometer, magnetometer), or with ``data=True`` (aided sim images) every
    input from a recording: the file :func:`data_file` writes, given to :class:`Session`.
    """
    if kind not in ("production", "sim", "bench"):
        raise ValueError(f"kind must be production, sim or bench, got {kind!r}")
    out_dir = Path(out_dir)
    name = name or f"fw_{kind}_{config.baud}" + ("" if config.link == "legacy" else "_v2") + (
        "_aided" if config.aided else "")
    code_size = config.flash_size if code_size is None else code_size
    objdir = out_dir / (name + ".objs")
    shutil.rmtree(objdir, ignore_errors=True)
    objdir.mkdir(parents=True, exist_ok=True)
    flags = _sdcc_flags(config.target)
    incs = [f"-I{CSRC / 'include'}", f"-I{FW_DIR}"]
    defines = ["ATT_REAL_F32", *config.defines(), *extra_defines]
    extra: list[str] = []
    sources = list(SOURCES_AIDED if config.aided else SOURCES if config.link == "legacy" else SOURCES_V2)
    if config.stream_n > 1:
        sources += SOURCES_SUMS
    fault_defs = {"dout_stuck_high": "FW_SIM_DOUT_STUCK=1", "dout_stuck_low": "FW_SIM_DOUT_STUCK=0",
                  "eoc_stuck": "FW_SIM_EOC_STUCK=1"}
    faults = list(faults)
    if faults and kind != "sim":
        raise ValueError("faults need kind='sim'")
    if kind in ("sim", "bench"):
        defines += ["FW_SIM", f"FW_SIM_BLOCKS={int(sim_blocks)}", f"FW_SIM_SAMPLES={int(sim_samples)}"]
        if config.aided:
            defines.append("FW_SIM_C52")  # the C52 core's Timer 2 SFRs: the instrumentation moves aside
        sources.append(FW_DIR / "sim" / "sim_io.c")
    if data and (kind != "sim" or not config.aided):
        raise ValueError("data=True needs kind='sim' and the aided board (board='aided9')")
    if kind == "sim":
        defines += ["FW_SIM_MODEL", *_gyro_defines(gyros, aux if config.aided else ()),
                    *(["FW_SIM_DATA"] if data else [])]
        for f in faults:
            fault, _, arg = f.partition("=")
            if fault == "adc_error_at" and arg.isdigit() and int(arg) < 256:
                defines.append(f"FW_SIM_EOC_STUCK_AT={int(arg)}")
                continue
            if f not in fault_defs:
                raise ValueError(f"unknown fault {f!r}; known: {sorted(fault_defs)} and adc_error_at=K "
                                 f"(0 <= K < 256)")
            defines.append(fault_defs[f])
        extra.append(f"-Wp-include,{SIM_HAL_HEADER}")
        sources.insert(1, FW_DIR / "sim" / "tlc_model.c")
    if kind == "bench":
        defines += ["FW_BENCH"]
    link_flags = _without_code_size(flags) + ["--code-size", str(code_size)]
    if kind != "production":
        # The simulation images carry the device model / counters and the
        # simulator-interface output: they may exceed the flash (s51's code
        # memory is 64 KB); RAM stays the chip's.
        link_flags = _without_code_size(flags) + ["--code-size", "65536"]
    if config.aided:
        sources.append(_crc_table_source(objdir / "crc32c_table.c"))
    rels = []
    for src in sources:
        rel = objdir / (src.stem + ".rel")
        _run(["sdcc", *flags, *incs, *[f"-D{d}" for d in defines], *extra, "-c", str(src), "-o", str(rel)])
        rels.append(str(rel))
    ihx = out_dir / (name + ".ihx")
    # Link with the 4 KB / 128 B limits of the chip: sdld fails when they are exceeded.
    proc = subprocess.run(["sdcc", *link_flags, *rels, "-o", str(ihx)], check=False, capture_output=True,
                          text=True)
    mem = ihx.with_suffix(".mem")
    if proc.returncode != 0:
        msg = proc.stdout + proc.stderr
        if "Insufficient" in msg or "Could not get" in msg:
            chip = "AT89S52" if config.aided else "AT89S51"
            raise FirmwareTooBig(f"{name} does not fit the {chip} ({code_size} B flash, "
                                 f"{config.iram_size} B RAM):\n{msg}")
        raise FirmwareError(f"link failed for {name}:\n{msg}")
    flash, stack_start, stack_free = parse_mem(mem)
    img = Image(ihx=ihx, kind=kind, config=config, flash=flash, ram_static=stack_start,
                stack_start=stack_start, stack_free=stack_free)
    if ((kind == "production" and flash > code_size) or stack_start + stack_free > config.iram_size
            or stack_free <= 0):
        raise FirmwareTooBig(img.size_report())
    return img


def data_records(config: Config, n: int) -> int:
    """Sample records (gyro, accelerometer, magnetometer) of an aided stream's first n samples."""
    def due(every: int) -> int:
        return 0 if every == 0 else (n + every - 1) // every
    return n + due(config.acc_every) + due(config.mag_every)


def data_file(path: Path | str, config: Config, gyro: np.ndarray, acc: np.ndarray, mag: np.ndarray) -> int:
    """Write the input of a ``data=True`` image (firmware/sim/tlc_model.c FW_SIM_DATA): per
    sample n the three gyro codes (of each of its ``gyro_oversample`` sub-scans, in time
    order), then the accelerometer's if n % acc_every == 0, then the magnetometer's if
    n % mag_every == 0 (the scan's order), each code two bytes big-endian. Arrays (N, 3) of
    12-bit codes, the gyros' (N, gyro_oversample, 3) when that is > 1; returns the sample
    records the firmware sends for them."""
    arrays = [np.asarray(a, dtype=np.int64) for a in (gyro, acc, mag)]
    ovs = config.gyro_oversample
    g, a, m = arrays
    if ovs > 1 and (g.ndim != 3 or g.shape[1:] != (ovs, 3)):
        raise ValueError(f"gyro must be codes of shape (N, {ovs}, 3) (gyro_oversample {ovs}), got {g.shape}")
    g = g.reshape(g.shape[0], 3 * ovs) if g.ndim == 3 else g
    if (g.ndim != 2 or g.shape[1] != 3 * ovs
            or any(x.ndim != 2 or x.shape != (g.shape[0], 3) for x in (a, m))):
        raise ValueError(f"gyro, acc, mag must be code arrays of one shape (N, 3), got {[x.shape for x in arrays]}")
    if any(x.size and (x.min() < 0 or x.max() > 4095) for x in arrays):
        raise ValueError("gyro, acc, mag must be 12-bit codes (0..4095)")
    recs, n_rec = [], 0
    for k in range(g.shape[0]):
        recs += list(g[k].reshape(-1, 3))
        n_rec += 1
        for x, every in ((a, config.acc_every), (m, config.mag_every)):
            if every and k % every == 0:
                recs.append(x[k])
                n_rec += 1
    Path(path).write_bytes(np.asarray(recs, dtype=">u2").tobytes())
    return n_rec


# -- the block stream -------------------------------------------------------

@dataclass
class Sample:
    seq: int
    codes: tuple[int, int, int]


#: A report record as libattitude's decoder read it (kind, raw, first, count, status,
#: bad_code, attempt, period_ticks, baud, ...): attitude_c.link.block.Record.
Report = block.Record


def decode_stream(blocks: Iterable[bytes]) -> list[Sample | Report]:
    """Number the samples of a block stream with libattitude's decoder and
    sequence tracker (attitude/block.h, through ``attitude_c.link.block``).

    Samples are counted from 0 after BOOT; a gave_up / overrun / adc_error
    report says which samples will never come, and must start exactly at
    the next number. Any record that breaks the format, or a loss report
    that disagrees with the count, raises :class:`FirmwareError`.
    """
    blocks = [bytes(b) for b in blocks]
    for b in blocks:
        if len(b) != BLOCK_SIZE:
            raise FirmwareError(f"block of {len(b)} bytes, expected {BLOCK_SIZE}: {b.hex()}")
    try:
        numbered = block.number_stream(blocks)
    except BlockFormatError as exc:
        raise FirmwareError(str(exc)) from exc
    return [Sample(span.first, rec.codes) if rec.kind == "sample" else rec for rec, span in numbered]


# -- host end of the link -----------------------------------------------------

@dataclass
class Attempt:
    """One data block the host received (what the firmware sent, before fault injection)."""

    index: int            #: number of blocks accepted before it
    data: bytes           #: N data bytes + checksum as on the wire
    answer: int | None    #: 0x00 / 0xFF, None if the receiver dropped it


class _Receiver:
    """Receiver B of libattitude (``attitude_c.link``): the C machine or the Python one."""

    def __init__(self, impl: Any, block_size: int, gap_timeout: int) -> None:  # attitude_c.link.cends.Impl
        from attitude_c.link.cends import make_receiver

        self.r = make_receiver(impl, block_size=block_size, gap_timeout=gap_timeout)

    def sink(self, byte: int, tick: int) -> str:
        return str(self.r.sink(byte, tick & 0xFFFF).name.lower())

    def poll(self, tick: int) -> tuple[str, int]:
        res, out = self.r.poll(tick & 0xFFFF)
        return str(res.name.lower()), (out if out is not None else -1)

    def block(self) -> bytes:
        return bytes(self.r.block)

    def stats(self) -> dict[str, int]:
        return dict(self.r.stats.as_dict())


class LinkHost:
    """The Linux side on the host end of the pty: receiver B plus fault injection.

    ``impl``: ``"c"`` (libattitude's C receiver through CFFI) or ``"python"``
    (the Python receiver of :mod:`attitude_c.link`, written from the spec).

    ``nak_blocks``: indices n (number of blocks accepted so far) whose first
    attempt gets one data bit flipped before the receiver sees it, so the
    receiver itself answers 0xFF. ``silent``: n -> how many 0xAA to ignore
    while n blocks have been accepted (no 0xBB: the firmware times out).
    Ticks are milliseconds of the host's clock: wall time, or s51's simulated
    time when :func:`run` drives s51 in lockstep (:meth:`use_clock`). The gap
    timeout is long (1 s) because on a wall clock s51 runs slower than real
    time and may be descheduled on a loaded machine: the firmware's own
    timeouts (simulated time) are what the tests exercise.
    """

    def __init__(self, impl: str = "c", *, block_size: int = BLOCK_SIZE, gap_timeout_ms: int = 1000,
                 nak_blocks: Iterable[int] = (), silent: dict[int, int] | None = None) -> None:
        if impl not in ("c", "python"):
            raise ValueError(f"impl must be 'c' or 'python', got {impl!r}")
        self.rx = _Receiver(impl, block_size, gap_timeout_ms)
        self.n = block_size
        self.nak_blocks = set(nak_blocks)
        self.silent = dict(silent or {})
        self.blocks: list[bytes] = []
        self.attempts: list[Attempt] = []
        self.ignored_syn: list[int] = []      #: accepted count at each ignored 0xAA
        self.wire: list[tuple[str, int]] = []  #: ("A"|"B", byte) in order
        self.wire_t: list[float] = []          #: host clock time of each wire entry (s)
        self._data: bytearray | None = None
        self._corrupted: set[int] = set()
        self._clock: Callable[[], float] = time.monotonic
        self._t0 = time.monotonic()

    def use_clock(self, clock: Callable[[], float]) -> None:
        """Take ticks and wire times from ``clock`` (seconds, from 0) instead of wall time."""
        self._clock, self._t0 = clock, 0.0

    def tick(self) -> int:
        return int((self._clock() - self._t0) * 1000.0)

    def receive(self, data: bytes) -> bytes:
        """Bytes from the firmware; returns the bytes to send back."""
        out = bytearray()
        for b in data:
            self.wire.append(("A", b))
            self.wire_t.append(self._clock())
            now = self.tick()
            k = len(self.blocks)
            if self._data is None and b == 0xAA and self.silent.get(k, 0) > 0:
                self.silent[k] -= 1
                self.ignored_syn.append(k)
                continue
            fed = b
            if self._data is not None:
                if not self._data and k in self.nak_blocks and k not in self._corrupted:
                    self._corrupted.add(k)
                    fed = b ^ 0x01
                self._data.append(b)
            res = self.rx.sink(fed, now)
            if res in ("accepted", "rejected"):
                self.attempts.append(Attempt(k, bytes(self._data or b""), 0x00 if res == "accepted" else 0xFF))
                self._data = None
                if res == "accepted":
                    self.blocks.append(self.rx.block())
            out += self._poll(now)
        out += self._poll(self.tick())
        return bytes(out)

    def _poll(self, now: int) -> bytes:
        out = bytearray()
        while True:
            res, byte = self.rx.poll(now)
            if res == "send":
                out.append(byte)
                self.wire.append(("B", byte))
                self.wire_t.append(self._clock())
                if byte == 0xBB:
                    self._data = bytearray()
            elif res == "timeout":
                if self._data is not None:
                    self.attempts.append(Attempt(len(self.blocks), bytes(self._data), None))
                self._data = None
            else:
                return bytes(out)

    def stats(self) -> dict[str, int]:
        return self.rx.stats()


# -- simulation -------------------------------------------------------------

@dataclass
class SimOutput:
    """What one s51 run of a sim/bench image produced (whatever was on the host end)."""

    output: str                     #: text the firmware wrote through the simulator interface
    console: str                    #: s51 console (state command output included)
    stats: dict[str, int]           #: the firmware's STATS line
    bench: dict[str, int]           #: the BENCH line (bench images)
    max_sp: int                     #: highest stack pointer s51 saw
    sim_seconds: float              #: simulated time
    wall_seconds: float


@dataclass
class SimResult(SimOutput):
    host: LinkHost = None  # type: ignore[assignment]
    max_step_s: float = 0.0  #: lockstep: the longest step's simulated time (0: not in lockstep)

    @property
    def stream(self) -> list[Sample | Report]:
        return decode_stream(self.host.blocks)


def _kill_group(proc: subprocess.Popen[Any] | None) -> None:
    if proc is None or proc.poll() is not None:
        return
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    try:
        proc.wait(timeout=5)
    except subprocess.TimeoutExpired:
        pass


def _parse_kv(line_tag: str, text: str) -> dict[str, int]:
    m = re.search(rf"^{line_tag}((?: \w+=[0-9A-F]+)*)\s*$", text, re.MULTILINE)
    if not m:
        return {}
    return {k: int(v, 16) for k, v in re.findall(r"(\w+)=([0-9A-F]+)", m.group(1))}


class _Console:
    """s51's command console on its stdin/stdout pipes (``-c -``; no prompt on a pipe)."""

    def __init__(self, proc: subprocess.Popen[bytes], deadline: float, fail: Callable[[str], Exception]) -> None:
        assert proc.stdin is not None and proc.stdout is not None
        self.proc, self.deadline, self.fail = proc, deadline, fail
        self.out = bytearray()  #: everything the console printed

    def send(self, command: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(command.encode() + b"\n")
        self.proc.stdin.flush()

    def ask(self, command: str, until: re.Pattern[bytes]) -> re.Match[bytes]:
        """Send ``command``; wait (up to the deadline) until its output matches ``until``."""
        start = len(self.out)
        self.send(command)
        return self.expect(until, start, command)

    def expect(self, until: re.Pattern[bytes], start: int, command: str) -> re.Match[bytes]:
        """Wait (up to the deadline) until the output from ``start`` on matches ``until``."""
        assert self.proc.stdout is not None
        while (m := until.search(self.out, start)) is None:
            left = self.deadline - time.monotonic()
            if left <= 0 or self.proc.poll() is not None:
                raise self.fail(f"no answer to `{command}`")
            if select.select([self.proc.stdout], [], [], min(left, 1.0))[0]:
                self.out += os.read(self.proc.stdout.fileno(), 65536)
        return m


#: The end of a `step`'s report: the clock ticks it simulated (12 per machine cycle).
_STEPPED = re.compile(rb"Simulated (\d+) ticks .*\nHost usage: [^\n]*\n")


class Session:
    """A socat pty pair with s51 on one end (``with Session(image) as s:``).

    ``s.port`` is the host end (a pty path): give it to whatever plays the
    Linux computer (:class:`LinkHost` through :func:`run`, or a program such
    as ``attitude-rx``) *before* ``s.run()`` starts the firmware, so that its
    BOOT report finds a listener. Every process is killed on exit.

    ``lockstep=True``: no pty; the host end reads and writes s51's UART FIFOs
    itself (:meth:`read`, :meth:`write`) and :meth:`run_lockstep` advances
    simulated time only while the host is caught up (docs/firmware.md).
    """

    def __init__(self, image: Image, timeout: float = 60.0, data: Path | None = None, *,
                 lockstep: bool = False) -> None:
        if image.kind == "production":
            raise ValueError("a production image never stops in the simulator; build kind='sim' or 'bench'")
        for tool in ("s51", "socat"):
            if shutil.which(tool) is None:
                raise FirmwareError(f"{tool} not found (apt-get install sdcc-ucsim socat)")
        self.image = image
        self.timeout = timeout
        self.data = data  #: the simulator interface's input file (a data image's recording)
        self._tmp = Path(tempfile.mkdtemp(prefix="fwsim_"))
        # s51's UART on two FIFOs, not on a pty: on a terminal, uCsim opens its serial
        # control menu when the byte uart0_esc_char (^X) arrives, and link v2's ACKs carry
        # any byte value. socat joins the FIFOs to the host's pty.
        self._fw_in = self._tmp / "uart_fw_in"
        self._fw_out = self._tmp / "uart_fw_out"
        self.port = self._tmp / "uart_host"
        self._socat: subprocess.Popen[bytes] | None = None
        self._s51: subprocess.Popen[bytes] | None = None
        self._t0 = time.monotonic()
        self.lockstep = lockstep
        self._fds: list[int] = []  #: lockstep: the host's ends of the FIFOs (from s51, to s51)
        self.sim_seconds = 0.0     #: lockstep: simulated time so far
        self.max_step_s = 0.0      #: lockstep: the longest step's simulated time

    def __enter__(self) -> Session:  # noqa: PYI034 - typing.Self needs Python 3.11
        try:
            os.mkfifo(self._fw_in)
            os.mkfifo(self._fw_out)
            if self.lockstep:  # both open read-write: no open() waits for s51's end
                self._fds = [os.open(f, os.O_RDWR | os.O_NONBLOCK) for f in (self._fw_out, self._fw_in)]
                return self
            self._socat = subprocess.Popen(
                ["socat", f"OPEN:{self._fw_out},rdwr!!OPEN:{self._fw_in},rdwr", f"pty,raw,echo=0,link={self.port}"],
                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                start_new_session=True)
            while not self.port.exists():
                if self._socat.poll() is not None:
                    err = self._socat.stderr.read().decode() if self._socat.stderr else ""
                    raise FirmwareError(f"socat failed: {err}")
                if time.monotonic() - self._t0 > 10:
                    raise SimTimeout("socat did not create the pty pair within 10 s")
                time.sleep(0.01)
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        _kill_group(self._s51)
        _kill_group(self._socat)
        for fd in self._fds:
            os.close(fd)
        self._fds = []
        shutil.rmtree(self._tmp, ignore_errors=True)

    def read(self) -> bytes:
        """Lockstep: every byte the firmware's UART has sent and the host has not read."""
        out = bytearray()
        while True:
            try:
                chunk = os.read(self._fds[0], 4096)
            except BlockingIOError:
                return bytes(out)
            out += chunk

    def write(self, data: bytes) -> None:
        """Lockstep: bytes to the firmware's UART (in the FIFO before the next step)."""
        view = memoryview(data)
        while view:
            view = view[os.write(self._fds[1], view):]

    def sim_time(self) -> float:
        """Lockstep: simulated seconds since reset at the end of the last step."""
        return self.sim_seconds

    def _s51_cmd(self, *tail: str) -> list[str]:
        sif = f"if=sfr[0xff],out={self._tmp / 'sif.out'}" + (f",in={self.data}" if self.data is not None else "")
        return ["s51", "-t", "C52" if self.image.config.aided else "C51", "-R", "1",
                "-I", sif, "-S", f"in={self._fw_in},out={self._fw_out}", *tail]

    def run_lockstep(self, pump: Callable[[], None], describe: Callable[[], str] | None = None, *,
                     ahead: bool = False) -> SimOutput:
        """Run s51 in steps of :data:`LOCKSTEP_INSNS` instructions from its console, calling
        ``pump()`` (the host end: read everything, answer) between two steps, until the
        firmware stops itself. Simulated time stands still while the host works or is
        descheduled, so a byte the firmware sends is answered within the next step: at
        most :data:`LOCKSTEP_BOUND_S` simulated seconds later, whatever the machine's load.

        ``ahead``: one more step is always queued at s51's console, so s51 runs step k+1
        while ``pump()`` handles step k's bytes, and the command of step k+2 goes out only
        when that pump has returned. An answer then reaches the firmware within two steps of
        :data:`LOCKSTEP_AHEAD_INSNS` (the same bound, :data:`LOCKSTEP_BOUND_S`), at an
        instant of step k+1 that depends on the host's speed (no longer repeatable byte
        for byte), and s51 never idles between steps: its console, stopped with no command
        waiting, sleeps up to 100 ms before it looks again, which is most of a plain
        lockstep run's wall time. Errors as :meth:`run`."""
        sif_out = self._tmp / "sif.out"
        t_start = time.monotonic()

        def fail(what: str) -> Exception:
            return SimTimeout(f"s51 did not stop within {self.timeout} s ({what}); firmware output so far:\n"
                              + (sif_out.read_text(errors="replace") if sif_out.exists() else "")
                              + "\ns51 console (end):\n" + con.out.decode(errors="replace")[-3000:]
                              + (f"\nhost: {describe()}" if describe is not None else ""))

        self._s51 = subprocess.Popen(self._s51_cmd("-c", "-", str(self.image.ihx)), stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True,
                                     cwd=self._tmp)
        con = _Console(self._s51, t_start + self.timeout, fail)
        con.ask("expr uart0_check_often=1", re.compile(rb"^1$", re.MULTILINE))
        cmd, seen = f"step {LOCKSTEP_AHEAD_INSNS if ahead else LOCKSTEP_INSNS}", len(con.out)
        if ahead:
            con.send(cmd)
        while not (sif_out.exists() and re.search(r"^EXIT \d+$", sif_out.read_text(errors="replace"), re.MULTILINE)):
            con.send(cmd)
            m = con.expect(_STEPPED, seen, cmd)
            seen, step = m.end(), int(m.group(1)) / XTAL_HZ
            self.sim_seconds += step
            self.max_step_s = max(self.max_step_s, step)
            pump()
        if ahead:
            con.expect(_STEPPED, seen, cmd)  # the step queued ahead
        con.ask("state", _STATE_SP)  # printed after the clock line
        _kill_group(self._s51)
        return _sim_output(sif_out.read_text(errors="replace"), bytes(con.out), time.monotonic() - t_start)

    def run(self, pump: Any = None, describe: Any = None) -> SimOutput:
        """Start s51 and wait until the firmware stops itself (``pump()``, if given, is
        called in the loop: the host end's work); raise :class:`SimTimeout` after the
        session's timeout (``describe()`` adds the host end's view to the message) and
        :class:`FirmwareError` if the program did not stop through ``s51_exit`` with
        code 0 (e.g. the device model detected a protocol violation)."""
        sif_out = self._tmp / "sif.out"
        cmds = self._tmp / "cmds"
        # no `kill` command: s51 leaving through it writes a terminal reset to the UART's pty
        # (ESC [ ? 9 l, ESC [ 0 ; 0 ' z, ESC [ ! p: 16 bytes the host end would take for line
        # noise); once `state` has printed, the process group is killed instead (SIGKILL)
        cmds.write_text(f'file "{self.image.ihx}"\nexpr uart0_check_often=1\nrun\nstate\n')
        t_start = time.monotonic()
        # s51 at a lower priority (nice 10) than the host end: s51 runs in simulated time, the host
        # answers in wall time, and on a loaded machine a host that waits for the CPU while s51
        # runs on would show up, stretched, as latency in simulated time (overruns). Niced, s51
        # yields the CPU to the host whenever both are ready: the simulation slows down with the
        # machine instead of running away from its host.
        self._s51 = s51 = subprocess.Popen(
            ["nice", "-n", str(S51_NICE), *self._s51_cmd("-C", str(cmds))], stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True, cwd=self._tmp)
        assert s51.stdout is not None
        os.set_blocking(s51.stdout.fileno(), False)
        out = bytearray()
        deadline = time.monotonic() + self.timeout
        while s51.poll() is None:
            chunk = s51.stdout.read()
            if chunk:
                out += chunk
            if _STATE_SP.search(out) and _STATE_CLOCK.search(out):
                break  # stopped, and `state` has printed: done
            if time.monotonic() > deadline:
                _kill_group(s51)
                raise SimTimeout(f"s51 did not stop within {self.timeout} s; firmware output so far:\n"
                                 + (sif_out.read_text(errors="replace") if sif_out.exists() else "")
                                 + "\ns51 console (end):\n" + out.decode(errors="replace")[-3000:]
                                 + (f"\nhost: {describe()}" if describe is not None else ""))
            if pump is not None:
                pump()
            else:
                time.sleep(0.02)
        _kill_group(s51)
        try:
            out += s51.stdout.read() or b""
        except (OSError, ValueError):
            pass
        output = sif_out.read_text(errors="replace") if sif_out.exists() else ""
        return _sim_output(output, bytes(out), time.monotonic() - t_start)


def _sim_output(output: str, out: bytes, wall: float) -> SimOutput:
    """The run's result from the firmware's output and s51's console (``state`` printed)."""
    console = out.decode(errors="replace")
    m = re.search(r"^EXIT (\d+)$", output, re.MULTILINE)
    if m is None or int(m.group(1)) != 0:
        raise FirmwareError(f"firmware did not stop cleanly (EXIT 0); output:\n{output}\n"
                            f"console:\n{console[-2000:]}")
    sp = _STATE_SP.search(out)
    clk = _STATE_CLOCK.search(out)
    if sp is None or clk is None:
        raise FirmwareError(f"no s51 state report in the console:\n{console[-2000:]}")
    return SimOutput(output=output, console=console, stats=_parse_kv("STATS", output),
                     bench=_parse_kv("BENCH", output), max_sp=int(sp.group(1), 16),
                     sim_seconds=float(clk.group(1)), wall_seconds=wall)


_STATE_SP = re.compile(rb"Max value of stack pointer= 0x([0-9a-fA-F]+)")
_STATE_CLOCK = re.compile(rb"Total time since last reset= ([0-9.]+) sec")


def _describe(host: LinkHost) -> str:
    return f"{len(host.wire)} bytes on the wire, last {host.wire[-12:]}, receiver {host.stats()}"


def _run_lockstep(image: Image, host: LinkHost, timeout: float) -> SimResult:
    """:func:`run` with s51 in lockstep with ``host`` (on s51's simulated clock)."""
    with Session(image, timeout, lockstep=True) as sess:
        host.use_clock(sess.sim_time)

        def pump() -> None:
            data = sess.read()
            reply = host.receive(data) if data else host._poll(host.tick())
            if reply:
                sess.write(reply)

        out = sess.run_lockstep(pump, lambda: _describe(host))
    return SimResult(**vars(out), host=host, max_step_s=sess.max_step_s)


def run(image: Image, host: LinkHost | None = None, *, timeout: float = 60.0, lockstep: bool = True) -> SimResult:
    """Run a sim/bench image in ``s51 -t C51`` with its UART on a pty pair and ``host`` on the other end.

    ``lockstep`` (the default): s51 runs in steps from its console with ``host`` on its
    UART's FIFOs, and simulated time advances only while the host is caught up, so the
    firmware sees every host answer at most :data:`LOCKSTEP_BOUND_S` simulated seconds
    late, however the OS schedules the host (docs/firmware.md "Lockstep"); the host's
    ticks are simulated milliseconds. ``lockstep=False``: s51 runs freely (niced) and the
    host answers over the pty in wall time, as any program on the pty does.

    The firmware stops itself (simulator interface) after the configured
    number of accepted blocks; s51 then prints its ``state`` (maximum stack
    pointer) and is killed. Raises :class:`SimTimeout` if
    that has not happened after ``timeout`` wall-clock seconds, and
    :class:`FirmwareError` if the program did not stop through ``s51_exit``
    with code 0 (e.g. the device model detected a protocol violation).
    """
    import serial  # pyserial

    host = host or LinkHost()
    if lockstep:
        return _run_lockstep(image, host, timeout)
    with Session(image, timeout) as sess:
        port = serial.Serial(str(sess.port), image.config.baud, timeout=0.01)

        def pump() -> None:
            data = port.read(max(1, port.in_waiting))
            reply = host.receive(data) if data else host._poll(host.tick())
            if reply:
                port.write(reply)

        try:
            out = sess.run(pump, lambda: _describe(host))
        finally:
            port.close()
    return SimResult(**vars(out), host=host)


@dataclass
class V2Result(SimOutput):
    """A link v2 image's run: the firmware's output, the records the receiver delivered
    in order, and the receiver's statistics."""

    records: list[bytes] = None  # type: ignore[assignment]
    receiver: dict[str, int] = None  # type: ignore[assignment]


def run_v2(image: Image, impl: Literal["c", "python"] = "c", *, timeout: float = 60.0,
           room: int = 64, late: bool = False, data: Path | None = None, lockstep: bool = False) -> V2Result:
    """Run a link v2 sim/bench image in s51 with libattitude's v2 receiver B on the pty:
    the C machine (``impl="c"``, through CFFI) or the Python one written from the spec
    (``data``: a ``data=True`` image's input file, :func:`data_file`).
    The host keeps up with any rate: its room never shrinks. ``late``: once records flow,
    the host holds its answers back until the firmware has sent a frame again (its
    retransmission timeout ran out), as a host descheduled on a loaded machine does;
    waiting for that event, not for a time, makes it certain. ``lockstep``: s51 in lockstep
    with the receiver (:meth:`Session.run_lockstep`, ``ahead=True``): every answer reaches
    the firmware within :data:`LOCKSTEP_BOUND_S` of simulated time whatever the machine's
    load, so what the firmware delivers is its own figure, not the host's (not with ``late``)."""
    import serial  # pyserial

    from attitude_c.link.v2 import Receiver2, Result2
    from attitude_c.link.v2c import CReceiver2

    if image.config.link != "v2":
        raise ValueError(f"run_v2 needs a link v2 image, got link={image.config.link!r}")
    if lockstep and late:
        raise ValueError("run_v2: late needs the free-running host (lockstep=False)")
    rx: Any = CReceiver2(room=room) if impl == "c" else Receiver2(room=room)
    got: list[bytes] = []
    reply = bytearray()

    def take(data_in: bytes) -> bytes:
        """The receiver fed ``data_in``: the answer bytes it has to send now."""
        for b in data_in:
            if rx.sink(b) == Result2.DELIVERED:
                got.extend(rx.delivered)
                rx.set_room(room)
        while True:
            res, byte = rx.poll()
            if res != Result2.SEND or byte is None:
                break
            reply.append(byte)
        if not reply or (late and got and rx.stats.duplicates == 0):
            return b""
        out = bytes(reply)
        reply.clear()
        return out

    def describe() -> str:
        return f"{len(got)} records, receiver {rx.stats.as_dict()}"

    with Session(image, timeout, data, lockstep=lockstep) as sess:
        if lockstep:
            fw = sess.run_lockstep(lambda: sess.write(take(sess.read())), describe=describe, ahead=True)
        else:
            port = serial.Serial(str(sess.port), image.config.baud, timeout=0.005)
            try:
                fw = sess.run(pump=lambda: port.write(take(port.read(max(1, port.in_waiting)))), describe=describe)
            finally:
                port.close()
    return V2Result(**vars(fw), records=got, receiver=dict(rx.stats.as_dict()))


# -- the simulator's acquisition source "s51" ---------------------------------------

#: (offset, shift, phase, step) per axis of the simulator's firmware runs. X, Y: a
#: quadrature pair (phase of X = phase of Y + 64, a quarter turn) about mid-scale,
#: ±512 LSB (shift 2), 4 cycles per 256 samples (0.20 Hz at h = 0.08 s); Z: a constant
#: −95.5 LSB (offset 31240 = 32768 − 1528: the middle of a code, so truncation loses nothing).
FW_GYROS = ((32768, 2, 64, 4), (32768, 2, 0, 4), (31240, 0, 0, 0))


def _qz(angle: np.ndarray) -> np.ndarray:
    a = np.asarray(angle, dtype=float)
    q = np.zeros(a.shape + (4,))
    q[..., 0] = np.cos(a / 2)
    q[..., 3] = np.sin(a / 2)
    return q


@dataclass
class FirmwareTrajectory(Trajectory):
    """Body rates of the firmware image's gyro model, with a closed-form truth.

    The image's model inputs are sinusoids of integer parameters (:class:`Gyro`:
    input = (offset + 32767 sin(2π(phase + k·step)/256) / 2^shift) / 65536 · Vref
    for sample k), mapped to rad/s by the host's rad/s per code. The parameters
    make a motion with a closed form: X and Y a quadrature pair of equal
    amplitude A (X = A cos β, Y = A sin β, β advancing at Ω), Z a constant rate
    c. The body rate ω(t) = R_z(β(t))·[A, 0, c] turns about the body z axis at
    Ω, and in a frame turning with it the rate is constant, so

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
        return quat_multiply(quat_multiply(_qz(np.full_like(t, self._b0)), turn), _qz(-self._beta(t)))

    def params(self) -> dict[str, Any]:
        return {"trajectory": self.name, "gyros_offset_shift_phase_step": [list(g) for g in self.gyros],
                "rate_amplitude_xy_dps": math.degrees(self._amp), "rate_z_dps": math.degrees(self._c),
                "frequency_hz": self._w / (2 * math.pi),
                "truth": "closed form: q_z(β0) ⊗ q(u t) ⊗ q_z(−β(t))"}


def firmware_available() -> bool:
    """Whether sdcc, s51 and socat are installed (the source's tools)."""
    return all(shutil.which(t) for t in ("sdcc", "s51", "socat"))


def _trajectory(period: float, gyro: GyroModel, cond: Conditioning, duration: float) -> FirmwareTrajectory:
    """The firmware's motion as the host reads it: the gyro preset through the conditioning."""
    k = cond.vref / 4096 / (gyro.scale_v_per_dps / DEG * cond.gain(gyro))
    return FirmwareTrajectory(period=period, rad_per_s_per_code=k, duration=duration)


def _check(cfg: SimConfig) -> None:
    if not isinstance(cfg.trajectory, FirmwareTrajectory):
        raise InvalidArgument("firmware='s51' runs the firmware's own gyro model: use a "
                              "FirmwareTrajectory (python -m toolchain.simulate --firmware s51 does)")
    if cfg.sensors == "ideal" or cfg.ber > 0:
        raise InvalidArgument("firmware='s51' takes the firmware's codes: sensors must "
                              "not be 'ideal' and ber must be 0 (the pty link is clean)")


def _acquire(cfg: SimConfig, n: int, progress: Callable[[str, int, int], None] | None) -> SourceOutput:
    """Build and run the firmware's simulation image for n samples: the blocks its
    host end accepted, and the host's calibration of the in-image model."""
    traj = cfg.trajectory
    assert isinstance(traj, FirmwareTrajectory)
    ticks = cfg.period * TICK_HZ
    if abs(ticks - round(ticks)) > 1e-6 or not 1 <= round(ticks) <= 32767:
        raise InvalidArgument(f"--firmware s51 needs a period that is a whole number of the "
                              f"firmware's 1/{TICK_HZ} s ticks, got {cfg.period} s")
    try:
        # Link timeouts of 1 s of simulated time (the chip's default is 50 ms): a firmware
        # resend of a block the host already accepted (the protocol's duplicate, docs/link.md)
        # would shift the numbering of the samples after it. run() drives s51 in lockstep, so
        # an answer is at most LOCKSTEP_BOUND_S late; the long timeouts are the margin.
        fw_cfg = Config(period_ticks=round(ticks), max_attempts=cfg.link_attempts, syn_timeout=3600,
                        answer_timeout=3600)
        # every run builds its own image in its own directory: two runs at once (pytest -n 2)
        # must never run, or link, each other's half-written image
        with tempfile.TemporaryDirectory(prefix="fw_source_") as tmp:
            img = build(Path(tmp), fw_cfg, kind="sim", sim_blocks=n + 1, gyros=[Gyro(*g) for g in traj.gyros],
                        name="fw_sim_attitude")
            if progress is not None:
                progress("s51", 0, n)
            res = run(img, timeout=max(60.0, 3.0 * n * cfg.period + 30.0))
    except (FirmwareError, OSError, ValueError) as exc:
        raise DeviceError(f"firmware run in s51 failed: {exc}") from exc
    if progress is not None:
        progress("s51", n, n)
    stats = {"link": "firmware (s51) → pty → C receiver", "backend": "s51 firmware", "ber": 0.0,
             "sent": int(res.stats.get("sent", 0)), "duplicated": 0, "corrupted_undetected": 0,
             "firmware_stats": dict(res.stats), "receiver": dict(res.host.stats()),
             "max_stack_pointer": res.max_sp, "simulated_s": res.sim_seconds, "wall_s": res.wall_seconds,
             "flash_bytes": img.flash}
    # one truncating conversion per period (the in-image model: code = v >> 4)
    calib = Calibration(np.full(3, 2047.5), traj.rad_per_s_per_code, 1)
    backends = {"sensors": "AT89S51 firmware in s51 (TLC2543 + gyro model in the image)",
                "link": "firmware link sender → pty → C receiver"}
    return SourceOutput(Delivered(list(res.host.blocks), None, stats), calib, backends)


#: The source (registered on import).
SOURCE = Source(name="s51", description="the AT89S51 firmware image in s51, its UART on a pty to the C receiver",
                acquire=_acquire, check=_check, trajectory=_trajectory)
register_source(SOURCE)
