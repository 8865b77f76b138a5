"""AD7927 8-channel 12-bit SPI ADC: the C driver, its device model and a reference driver.

* :class:`Ad7927` — the C driver (csrc/src/ad7927.c, the source every target
  builds) reading a device model through either HAL: ``hal="pins"`` (the
  bit-banged HAL, pin callbacks) or ``hal="frames"`` (the frame-transfer HAL
  of a hardware SPI controller). The model is the Python
  :class:`Ad7927Model` (raises :class:`ProtocolViolation` on any protocol or
  timing error, records a pin trace and a frame log) or its C twin
  :class:`CTwin` (same behaviour, fast).
* :func:`convert` — batch conversion voltages (N, k) -> codes (N, k) through
  the C driver against the C twin, with fault injection; :func:`codes_to_volts`
  is its inverse (bin centres). A simulator stage wraps these two.
* :class:`ReferenceDriver` — a pure-Python driver written from the
  datasheet, the second opinion in the tests.
* :data:`THESIS_BOARD` — the UAV thesis's wiring (S3C2440 SPI0 at 9.26 MHz,
  REFIN 2.5 V, 0-5 V inputs, the channel map of its Fig. 4.6).

Status codes and constants are read from the compiled library. Docs:
docs/ad7927.md.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Callable, Literal

import numpy as np

from .._devmodel import CTwinBase, check_level, convert_in_chunks, raise_model_error
from ..errors import InvalidArgument, InvalidType, NonFiniteError
from ..names import raise_for_status
from . import _capi
from ._errors import AddressMismatch, FrameError
from .model import (
    HIGH_Z,
    POWERUP_CONTROL,
    RULES,
    SIGNALS,
    Ad7927Model,
    Frame,
    ProtocolViolation,
    Timing,
    quantize,
    shadow_channels,
)
from .reference import ReferenceDriver, control_word, shadow_word

__all__ = [
    "HIGH_Z",
    "RULES",
    "SIGNALS",
    "THESIS_BOARD",
    "Ad7927",
    "Ad7927Model",
    "AddressMismatch",
    "Board",
    "CTwin",
    "Frame",
    "FrameError",
    "ProtocolViolation",
    "ReferenceDriver",
    "Timing",
    "codes_to_volts",
    "control_word",
    "convert",
    "quantize",
    "shadow_channels",
    "shadow_word",
]

Hal = Literal["pins", "frames"]
Mode = Literal["scan", "sequence"]


@dataclass(frozen=True)
class Board:
    """How an AD7927 is wired: SPI clock, reference, range, what each input carries."""

    spi_hz: int
    refin: float
    range_double: bool
    channels: dict[str, int] = field(default_factory=dict)


#: The UAV thesis's flight computer (arm-uav-flight-control-thesis sec. 4.2.5,
#: 4.5, Fig. 4.6): SPI0 at PCLK/2 = 9.26 MHz, REFIN 2.5 V, 0-5 V inputs
#: (RANGE = 0), gyro rates, temperature and accelerometers on VIN0..VIN6,
#: the 2.5 V reference on VIN7 (channel order read from the figure: an
#: interpretation, see docs/ad7927.md).
THESIS_BOARD = Board(spi_hz=9_260_000, refin=2.5, range_double=True, channels={
    "gyro_x": 0, "gyro_y": 1, "gyro_z": 2, "temperature": 3,
    "accel_x": 4, "accel_y": 5, "accel_z": 6, "ref_2v5": 7})


def _check_hal(hal: str) -> bool:
    if hal not in ("pins", "frames"):
        raise InvalidArgument(f"hal must be 'pins' or 'frames', got {hal!r}")
    return hal == "frames"


def _channel(name: str, v: Any) -> int:
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
        raise InvalidType(f"{name} must be an int 0..7, got {type(v).__name__}")
    if not 0 <= int(v) <= 7:
        raise InvalidArgument(f"{name} must be a channel 0..7, got {v!r}")
    return int(v)


class CTwin(CTwinBase[ProtocolViolation]):
    """The C twin of :class:`Ad7927Model` (csrc/host/ad7927_model.c).

    Same arguments and behaviour; violations are latched (:meth:`violation`)
    and raised by :class:`Ad7927` after the driver call. ``trace_capacity``
    pin events and ``frames_capacity`` frames are recorded (0 = none).
    """

    _SET_INPUTS = ("ad7927m_set_inputs", 8, "VIN")
    _SIGNALS = SIGNALS
    _RULES = RULES
    _VIOLATION = ProtocolViolation

    def __init__(self, inputs: Sequence[float] | np.ndarray = (), *, refin: float = 2.5,
                 powerup_control: int = POWERUP_CONTROL, powerup_shadow: bool = True,
                 stuck_dout: int | None = None, stuck_din: int | None = None, address_xor: int = 0,
                 sclk_period_ns: int = 108, trace_capacity: int = 100_000,
                 frames_capacity: int = 10_000, precision: str = "f64") -> None:
        ffi, lib = _capi.register(precision)
        self._ffi, self._lib = ffi, lib
        self._m = ffi.new("ad7927m *")
        if not 0 <= int(powerup_control) <= 0xFFF:
            raise InvalidArgument(f"powerup_control must be a 12-bit word, got {powerup_control!r}")
        st = lib.ad7927m_init(self._m, float(refin), int(powerup_control), 1 if powerup_shadow else 0)
        raise_for_status(st, "CTwin(refin, powerup_control)")
        self._m.stuck_dout = check_level("stuck_dout", stuck_dout)
        self._m.stuck_din = check_level("stuck_din", stuck_din)
        if not 0 <= int(address_xor) <= 7:
            raise InvalidArgument(f"address_xor must be 0..7, got {address_xor!r}")
        self._m.address_xor = int(address_xor)
        if int(sclk_period_ns) < 1:
            raise InvalidArgument(f"sclk_period_ns must be positive, got {sclk_period_ns!r}")
        self._m.sclk_period_ns = int(sclk_period_ns)
        self._trace = ffi.new("ad7927m_event[]", max(int(trace_capacity), 1)) if trace_capacity else ffi.NULL
        self._m.trace, self._m.trace_cap = self._trace, int(trace_capacity)
        self._frames = ffi.new("ad7927m_frame[]", max(int(frames_capacity), 1)) if frames_capacity else ffi.NULL
        self._m.frames, self._m.frames_cap = self._frames, int(frames_capacity)
        self.set_inputs(inputs)

    def hal(self, kind: Hal) -> Any:
        """The model's ad7927_hal of that kind (the C driver points at it)."""
        return self._ffi.addressof(self._m, "frame_hal" if _check_hal(kind) else "pin_hal")

    @property
    def frames(self) -> list[Frame]:
        return _capi.frame_log(self._m)


class Ad7927:
    """The C AD7927 driver reading a device model through one of its HALs.

    ``model``: an :class:`Ad7927Model` (Python, via callbacks; default: a new
    one with 0 V inputs) or a :class:`CTwin`. ``hal``: ``"pins"`` (bit-banged)
    or ``"frames"`` (SPI controller). ``range_double``: 0..2 REFIN (else
    0..REFIN); ``twos_complement``: codes -2048..2047 (else 0..4095).
    """

    def __init__(self, model: Ad7927Model | CTwin | None = None, *, hal: Hal = "pins",
                 range_double: bool = True, twos_complement: bool = False,
                 precision: str = "f64") -> None:
        ffi, lib = _capi.register(precision)
        self._ffi, self._lib = ffi, lib
        frames = _check_hal(hal)
        self.model: Ad7927Model | CTwin = Ad7927Model() if model is None else model
        self._bridge: _capi.Bridge | None = None
        self._keep: tuple[Any, ...] = ()
        if isinstance(self.model, Ad7927Model):
            self._bridge = _capi.Bridge(self.model)
            self._hal, pins, handle = _capi.python_hal(ffi, lib, self._bridge, frames)
            self._keep = (pins, handle)
        elif isinstance(self.model, CTwin):
            self._hal = self.model.hal(hal)
        else:
            raise InvalidType(f"model must be an Ad7927Model or CTwin, got {type(model).__name__}")
        self._dev = ffi.new("ad7927 *")
        self._settings = ffi.new("ad7927_settings *")
        self._fill(range_double, twos_complement)
        raise_for_status(lib.ad7927_init(self._dev, self._hal, self._settings), "Ad7927(settings)")
        self.hal = hal

    def _fill(self, range_double: bool, twos_complement: bool) -> None:
        self._settings.range_double = 1 if range_double else 0
        self._settings.twos_complement = 1 if twos_complement else 0

    # -- plumbing -------------------------------------------------------------
    def _after(self, status: int, what: str) -> None:
        raise_model_error(self._bridge, self.model)
        if status in (self._lib.AD7927_E_CHANNEL, self._lib.AD7927_E_FRAME):
            word, exp = int(self._dev.last_word), int(self._dev.last_expect)
            cls = AddressMismatch if status == self._lib.AD7927_E_CHANNEL else FrameError
            name = "its leading bit is 1" if cls is FrameError else f"it names VIN{(word >> 12) & 7}"
            want = "" if exp >= 8 else f", expected VIN{exp}"
            raise cls(f"{what}: output word 0x{word:04X}: {name}{want} (status {status})", word, exp)
        raise_for_status(status, what, _capi.STATUS)

    # -- API ------------------------------------------------------------------
    @property
    def pending(self) -> int | None:
        """Channel the next frame converts (None: unknown)."""
        p = int(self._dev.pending)
        return None if p >= 8 else p

    @property
    def trace(self) -> list[tuple[int, str, int]]:
        """The model's pin trace: (t_ns, signal, value) tuples."""
        return self.model.trace

    @property
    def frames(self) -> list[Frame]:
        """The model's frame log."""
        return list(self.model.frames)

    def power_up(self) -> None:
        """The datasheet power-up: two DIN-high frames, then the first write."""
        self._after(self._lib.ad7927_power_up(self._dev), "ad7927_power_up")

    def scan(self, channels: Sequence[int] = (0, 1, 2, 3, 4, 5, 6),
             next_channel: int | None = None) -> np.ndarray:
        """Codes of ``channels`` (0..7, up to 16); the last frame writes
        ``next_channel`` (default channels[0]: the next scan of the same list
        then takes len(channels) frames)."""
        ch = np.asarray(channels)
        most, top = int(self._lib.AD7927_MAX_SCAN), int(self._lib.AD7927_CHANNELS) - 1
        if ch.ndim != 1 or ch.size == 0 or ch.size > most or ch.dtype.kind not in "iu":
            raise InvalidArgument(f"channels must be a 1-D list of 1..{most} ints, got {channels!r}")
        if np.any((ch < 0) | (ch > top)):
            raise InvalidArgument(f"channels must be 0..{top}, got {ch.tolist()}")
        nxt = int(ch[0]) if next_channel is None else _channel("next_channel", next_channel)
        cbuf = self._ffi.new("uint8_t[]", [int(c) for c in ch])
        codes = self._ffi.new("int16_t[]", ch.size)
        st = self._lib.ad7927_scan(self._dev, cbuf, ch.size, codes, nxt)
        self._after(st, f"ad7927_scan({ch.tolist()})")
        return np.array([codes[i] for i in range(ch.size)], dtype=np.int64)

    def seq_start(self, last: int) -> None:
        """Start the consecutive sequence VIN0..VIN``last``."""
        last = _channel("last", last)
        self._after(self._lib.ad7927_seq_start(self._dev, last), f"ad7927_seq_start({last})")

    def shadow_start(self, sequence_one: Sequence[int], sequence_two: Sequence[int] = ()) -> None:
        """Program the shadow register: the channels of ``sequence_one``
        ascending, then those of ``sequence_two``, around again."""
        masks = []
        for name, seq in (("sequence_one", sequence_one), ("sequence_two", sequence_two)):
            m = 0
            for c in seq:
                m |= 1 << _channel(name, c)
            masks.append(m)
        if masks[0] == 0:
            raise InvalidArgument("sequence_one must name at least one channel")
        st = self._lib.ad7927_shadow_start(self._dev, masks[0], masks[1])
        self._after(st, f"ad7927_shadow_start({list(sequence_one)}, {list(sequence_two)})")

    def seq_read(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """``n`` (1..16) conversions of the running sequence: (codes, channels)."""
        most = int(self._lib.AD7927_MAX_SCAN)
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= most:
            raise InvalidArgument(f"n must be an int 1..{most}, got {n!r}")
        codes = self._ffi.new("int16_t[]", int(n))
        chans = self._ffi.new("uint8_t[]", int(n))
        self._after(self._lib.ad7927_seq_read(self._dev, codes, chans, int(n)), f"ad7927_seq_read({n})")
        return (np.array([codes[i] for i in range(n)], dtype=np.int64),
                np.array([chans[i] for i in range(n)], dtype=np.int64))

    def configure(self, *, range_double: bool = True, twos_complement: bool = False) -> None:
        """New range/coding, sent with the next frame written."""
        self._fill(range_double, twos_complement)
        self._after(self._lib.ad7927_configure(self._dev, self._settings), "ad7927_configure")

    def power_down(self) -> None:
        """Full shutdown; the next scan or sequence start wakes the part."""
        self._after(self._lib.ad7927_power_down(self._dev), "ad7927_power_down")


def codes_to_volts(codes: np.ndarray, refin: float = 2.5, *, range_double: bool = True,
                   twos_complement: bool = False) -> np.ndarray:
    """Input voltage at the centre of each code's bin: the transitions are at
    whole LSBs (LSB = span / 4096, span = 2 REFIN or REFIN), so code c covers
    [c, c + 1) LSB; two's complement codes are offset by 2048."""
    c = np.asarray(codes)
    if c.dtype.kind not in "iu":
        raise InvalidType(f"codes must be an integer array, got dtype {c.dtype}")
    if not (np.isfinite(refin) and refin > 0):
        raise InvalidArgument(f"refin must be a positive finite voltage, got {refin!r}")
    lo, hi = (-2048, 2047) if twos_complement else (0, 4095)
    bad = np.flatnonzero(((c < lo) | (c > hi)).reshape(-1))
    if bad.size:
        raise InvalidArgument(f"codes: element {int(bad[0])} = {int(c.reshape(-1)[bad[0]])} is outside "
                              f"{lo}..{hi}")
    span = 2.0 * refin if range_double else refin
    straight = c.astype(float) + (2048.0 if twos_complement else 0.0)
    return (straight + 0.5) * (span / 4096.0)


def convert(volts: np.ndarray, refin: float = 2.5, *, channels: Sequence[int] | None = None,
            range_double: bool = True, twos_complement: bool = False, mode: Mode = "scan",
            hal: Hal = "frames", stuck_dout: int | None = None, stuck_din: int | None = None,
            address_xor: int = 0, progress: Callable[[int], None] | None = None, chunk: int = 8192,
            precision: str = "f64") -> np.ndarray:
    """Convert voltages (N, k) to codes (N, k) through the C driver and the C twin.

    Column j is wired to VIN ``channels[j]`` (default VIN0..VINk-1). The
    driver powers the part up, then reads one row per scan: ``mode="scan"``
    writes every channel (k frames per row in steady state), ``"sequence"``
    runs the consecutive sequence VIN0..VIN(k-1) with WRITE = 0 frames
    (channels must be 0..k-1). Every conversion of row i is sampled in row
    i's own frames. ``hal``: the frame-transfer HAL (an SPI controller) or
    the bit-banged pin HAL. Codes: 0..4095, or -2048..2047 with
    ``twos_complement``. Faults: ``stuck_dout``, ``stuck_din`` (0/1),
    ``address_xor`` (0..7). ``progress(rows_done)`` after each ``chunk`` rows.

    Errors (raised with ``codes`` = the rows converted so far and
    ``rows_done``): AddressMismatch, FrameError, ProtocolViolation,
    NonFiniteError (``index`` = row).
    """
    v = np.asarray(volts)
    if v.dtype.kind not in "fiu":
        raise InvalidType(f"volts must be a real array, got dtype {v.dtype}")
    v = np.ascontiguousarray(v, dtype=float)
    if v.ndim != 2 or not 1 <= v.shape[1] <= 8:
        raise InvalidArgument(f"volts must have shape (N, k) with 1 <= k <= 8, got {v.shape}")
    n, k = v.shape
    chans = list(range(k)) if channels is None else [int(c) for c in channels]
    if len(chans) != k or any(not 0 <= c <= 7 for c in chans) or len(set(chans)) != k:
        raise InvalidArgument(f"channels must be {k} distinct channels 0..7, got {channels!r}")
    if mode not in ("scan", "sequence"):
        raise InvalidArgument(f"mode must be 'scan' or 'sequence', got {mode!r}")
    if mode == "sequence" and chans != list(range(k)):
        raise InvalidArgument(f"mode='sequence' reads VIN0..VIN{k - 1} in order: channels must be "
                              f"{list(range(k))}, got {chans}")
    _check_hal(hal)
    if not (np.isfinite(refin) and refin > 0):
        raise InvalidArgument(f"refin must be a positive finite voltage, got {refin!r}")
    bad_rows = np.flatnonzero(~np.all(np.isfinite(v), axis=1))
    if bad_rows.size:
        raise NonFiniteError(f"volts: row {int(bad_rows[0])} holds NaN or Inf", index=int(bad_rows[0]))
    twin = CTwin(refin=refin, stuck_dout=stuck_dout, stuck_din=stuck_din, address_xor=address_xor,
                 trace_capacity=0, frames_capacity=0, precision=precision)
    drv = Ad7927(twin, hal=hal, range_double=range_double, twos_complement=twos_complement,
                 precision=precision)
    ffi, lib = drv._ffi, drv._lib
    cbuf = ffi.new("uint8_t[]", chans)
    done = ffi.new("size_t *")

    def step(row: int, m: int, first: bool, out: np.ndarray) -> tuple[int, int]:
        st = lib.ad7927m_convert(twin._m, drv._dev, cbuf, k, ffi.cast("double *", v[row:row + m].ctypes.data),
                                 m, ffi.cast("int32_t *", out[row:].ctypes.data),
                                 1 if mode == "sequence" else 0, 1 if first else 0, done)
        return int(st), int(done[0])

    return convert_in_chunks(n, k, chunk, step, lambda st: drv._after(st, "ad7927 convert"), progress)
