"""TLC2543 12-bit ADC: the C driver, its device model and a reference driver.

* :class:`Tlc2543` — the C driver (csrc/src/tlc2543.c, the same source the
  AT89S51 firmware uses) reading a device model: the pin-level Python model
  :class:`Tlc2543Model` (through CFFI callbacks; raises
  :class:`ProtocolViolation` on any protocol error, records a pin trace) or
  its C twin :class:`CTwin` (same behaviour, fast).
* :func:`convert` — batch conversion voltages (N, channels) -> codes through
  the C driver against the C twin, with fault injection (stuck EOC, stuck
  DATA OUT).
* :class:`ReferenceDriver` — a pure-Python driver written from the
  datasheet, the second opinion in the tests.

Docs: docs/tlc2543.md.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Callable

import numpy as np

from .._devmodel import CTwinBase, check_level, convert_in_chunks, raise_model_error
from ..errors import DeviceError, DeviceTimeout, InvalidArgument, InvalidType, NonFiniteError
from ..names import raise_for_status
from . import _capi
from .model import HIGH_Z, RULES, SIGNALS, ProtocolViolation, Timing, Tlc2543Model, quantize
from .reference import ReferenceDriver

__all__ = [
    "CH_X",
    "CH_Y",
    "CH_Z",
    "HIGH_Z",
    "POWER_DOWN",
    "RULES",
    "SIGNALS",
    "TEST_MID",
    "TEST_REFM",
    "TEST_REFP",
    "CTwin",
    "ProtocolViolation",
    "ReferenceDriver",
    "SelfTestError",
    "Timing",
    "Tlc2543",
    "Tlc2543Model",
    "convert",
    "quantize",
]

CH_X, CH_Y, CH_Z = 0, 1, 2
TEST_MID, TEST_REFM, TEST_REFP, POWER_DOWN = 11, 12, 13, 14
_LENGTH_CODE = {8: 1, 12: 0, 16: 3}


class SelfTestError(DeviceError):
    """The power-up self-test codes are off; ``codes`` = (mid, Vref-, Vref+)."""

    def __init__(self, message: str, codes: np.ndarray | None = None) -> None:
        super().__init__(message)
        self.codes = codes


#: The driver's and its model's status codes (attitude/tlc2543.h, csrc/host/tlc2543_model.h),
#: keyed by C name (attitude_c.names).
_STATUS = {
    "TLC2543_E_EOC_TIMEOUT": (DeviceTimeout, "EOC did not rise (conversion never ended): EOC stuck low?"),
    "TLC2543_E_SELFTEST_MID": (SelfTestError, "self-test: (Vref+ + Vref-)/2 code is not 0x800 +- 2"),
    "TLC2543_E_SELFTEST_REFM": (SelfTestError, "self-test: Vref- code is not 0x000 + 2"),
    "TLC2543_E_SELFTEST_REFP": (SelfTestError, "self-test: Vref+ code is not 0xFFF - 2"),
    "TLC2543M_E_VIOLATION": (ProtocolViolation, "protocol violation"),
}


def _check_length(length: int) -> int:
    if isinstance(length, bool) or not isinstance(length, (int, np.integer)):
        raise InvalidType(f"length must be an int (8, 12 or 16), got {type(length).__name__}")
    if int(length) not in _LENGTH_CODE:
        raise InvalidArgument(f"length must be 8, 12 or 16, got {length}")
    return int(length)


class CTwin(CTwinBase[ProtocolViolation]):
    """The C twin of :class:`Tlc2543Model` (csrc/host/tlc2543_model.c).

    Same arguments and behaviour; violations are latched (``violation``)
    and raised by :class:`Tlc2543` after the driver call. ``trace_capacity``
    events are recorded (0 = none).
    """

    _SET_INPUTS = ("tlc2543m_set_inputs", 11, "AIN")
    _SIGNALS = SIGNALS
    _RULES = RULES
    _VIOLATION = ProtocolViolation

    def __init__(self, inputs: Sequence[float] | np.ndarray = (), *, vref_plus: float = 5.0,
                 vref_minus: float = 0.0, stuck_eoc: int | None = None,
                 stuck_dout: int | None = None, powerup_word: int = 0xA5A,
                 trace_capacity: int = 100_000, precision: str = "f64") -> None:
        ffi, lib = _capi.register(precision)
        self._ffi, self._lib = ffi, lib
        self._m = ffi.new("tlc2543m *")
        st = lib.tlc2543m_init(self._m, float(vref_plus), float(vref_minus), int(powerup_word) & 0xFFFF)
        raise_for_status(st, "CTwin(vref_plus, vref_minus)")
        self._m.stuck_eoc = check_level("stuck_eoc", stuck_eoc)
        self._m.stuck_dout = check_level("stuck_dout", stuck_dout)
        if stuck_eoc is not None:
            self._m.eoc_level = stuck_eoc
        self._buf = ffi.new("tlc2543m_event[]", max(int(trace_capacity), 1)) if trace_capacity else ffi.NULL
        self._m.trace = self._buf
        self._m.trace_cap = int(trace_capacity)
        self.set_inputs(inputs)

    @property
    def hal(self) -> Any:
        return self._ffi.addressof(self._m, "hal")



class Tlc2543:
    """The C TLC2543 driver reading a device model.

    ``model`` is a :class:`Tlc2543Model` (Python, via callbacks; default: a
    new one with 0 V inputs) or a :class:`CTwin`. Settings as the C
    ``tlc2543_settings``: ``length`` 8/12/16 clocks, ``lsb_first``,
    ``bipolar`` (words are then returned sign-extended), ``eoc_polls`` (EOC
    samples, 1 us apart, before a timeout; 0 = the driver's default 40).
    """

    def __init__(self, model: Tlc2543Model | CTwin | None = None, *, length: int = 12,
                 lsb_first: bool = False, bipolar: bool = False, eoc_polls: int = 0,
                 precision: str = "f64") -> None:
        ffi, lib = _capi.register(precision)
        self._ffi, self._lib = ffi, lib
        self.model: Tlc2543Model | CTwin = Tlc2543Model() if model is None else model
        if isinstance(self.model, Tlc2543Model):
            self._bridge: _capi.Bridge | None = _capi.Bridge(self.model)
            self._hal, self._handle = _capi.python_hal(ffi, lib, self._bridge)
        elif isinstance(self.model, CTwin):
            self._bridge = None
            self._hal, self._handle = self.model.hal, None
        else:
            raise InvalidType(f"model must be a Tlc2543Model or CTwin, got {type(model).__name__}")
        if not isinstance(eoc_polls, (int, np.integer)) or not 0 <= eoc_polls <= 255:
            raise InvalidArgument(f"eoc_polls must be an int in 0..255, got {eoc_polls!r}")
        s = ffi.new("tlc2543_settings *")
        s.length = _LENGTH_CODE[_check_length(length)]
        s.lsb_first = 1 if lsb_first else 0
        s.bipolar = 1 if bipolar else 0
        s.eoc_polls = int(eoc_polls)
        self._dev = ffi.new("tlc2543 *")
        raise_for_status(lib.tlc2543_init(self._dev, self._hal, s), "Tlc2543(settings)")
        self.length = int(length)
        self.bipolar = bool(bipolar)

    # -- plumbing -------------------------------------------------------------
    def _after(self, status: int, what: str) -> None:
        raise_model_error(self._bridge, self.model)
        raise_for_status(status, what, _STATUS)

    def _signed(self, word: int) -> int:
        return int(self._lib.tlc2543_signed(self._dev, word)) if self.bipolar else int(word)

    # -- API --------------------------------------------------------------------
    @property
    def pending(self) -> int | None:
        """Address whose conversion the output register holds (None: nothing usable)."""
        p = int(self._dev.pending)
        return None if p >> 4 >= 14 else p >> 4

    @property
    def trace(self) -> list[tuple[int, str, int]]:
        """The model's pin trace: (t_ns, signal, value) tuples."""
        return self.model.trace

    def cycle(self, address: int) -> int:
        """One I/O cycle requesting ``address`` (0..14); returns the word
        clocked out (the previous request's conversion)."""
        if not isinstance(address, (int, np.integer)) or not 0 <= address <= 14:
            raise InvalidArgument(f"address must be an int in 0..14, got {address!r}")
        w = self._ffi.new("uint16_t *")
        self._after(self._lib.tlc2543_cycle(self._dev, int(address), w), f"tlc2543_cycle({address})")
        return self._signed(w[0])

    def scan(self, channels: Sequence[int] = (CH_X, CH_Y, CH_Z), next_address: int | None = None) -> np.ndarray:
        """Codes of ``channels`` (addresses 0..13) in the fewest I/O cycles.
        The last cycle requests ``next_address`` (default channels[0]: the next
        scan of the same list then takes len(channels) cycles)."""
        ch = np.asarray(channels)
        if ch.ndim != 1 or ch.size == 0 or ch.size > 255 or ch.dtype.kind not in "iu":
            raise InvalidArgument(f"channels must be a 1-D list of 1..255 ints, got {channels!r}")
        if np.any((ch < 0) | (ch > 13)):
            raise InvalidArgument(f"channels must be addresses 0..13, got {ch.tolist()}")
        nxt = int(ch[0]) if next_address is None else next_address
        if not isinstance(nxt, (int, np.integer)) or not 0 <= nxt <= 14:
            raise InvalidArgument(f"next_address must be an int in 0..14, got {next_address!r}")
        cbuf = self._ffi.new("uint8_t[]", [int(c) for c in ch])
        codes = self._ffi.new("uint16_t[]", ch.size)
        st = self._lib.tlc2543_scan(self._dev, cbuf, ch.size, codes, int(nxt))
        self._after(st, f"tlc2543_scan({ch.tolist()})")
        return np.array([self._signed(codes[i]) for i in range(ch.size)], dtype=np.int64)

    def self_test(self) -> np.ndarray:
        """Run the power-up self-test; returns the codes (mid, Vref-, Vref+) or
        raises :class:`SelfTestError` (with ``codes``) when they are off."""
        codes = self._ffi.new("uint16_t[3]")
        st = self._lib.tlc2543_self_test_codes(self._dev, codes)
        out = np.array([codes[0], codes[1], codes[2]], dtype=np.int64)
        try:
            self._after(st, "tlc2543_self_test")
        except SelfTestError as exc:
            exc.codes = out
            raise
        return out

    def power_down(self) -> None:
        """Software power-down (the next cycle wakes the chip)."""
        self._after(self._lib.tlc2543_power_down(self._dev), "tlc2543_power_down")


def convert(volts: np.ndarray, vref_plus: float = 5.0, *, vref_minus: float = 0.0,
            channels: Sequence[int] | None = None, length: int = 12, lsb_first: bool = False,
            bipolar: bool = False, self_test: bool = True, stuck_eoc: int | None = None,
            stuck_dout: int | None = None, eoc_polls: int = 0,
            progress: Callable[[int], None] | None = None, chunk: int = 8192,
            precision: str = "f64") -> np.ndarray:
    """Convert voltages (N, k) to codes (N, k) through the C driver and the C twin.

    Column j is wired to AIN ``channels[j]`` (default AIN0..AINk-1: X, Y, Z
    for k = 3). Each row is one full scan (k + 1 I/O cycles) of that row's
    voltages, so row i's codes come from row i only. Codes: 8/12/16-bit
    words (12-bit: 0..4095; bipolar: signed). ``self_test`` runs the driver's
    power-up self-test first. Faults: ``stuck_eoc`` (0/1) and ``stuck_dout``
    (0/1). ``progress(rows_done)`` is called after each ``chunk`` rows.

    Errors (raised with ``codes`` = the rows converted so far and
    ``rows_done``): DeviceTimeout (EOC stuck low), SelfTestError (e.g. DATA OUT
    stuck), ProtocolViolation, NonFiniteError (``index`` = row).
    """
    v = np.asarray(volts)
    if v.dtype.kind not in "fiu":
        raise InvalidType(f"volts must be a real array, got dtype {v.dtype}")
    v = np.ascontiguousarray(v, dtype=float)
    if v.ndim != 2 or v.shape[1] < 1 or v.shape[1] > 11:
        raise InvalidArgument(f"volts must have shape (N, k) with 1 <= k <= 11, got {v.shape}")
    n, k = v.shape
    chans = list(range(k)) if channels is None else [int(c) for c in channels]
    if len(chans) != k or any(not 0 <= c <= 10 for c in chans) or len(set(chans)) != k:
        raise InvalidArgument(f"channels must be {k} distinct AIN numbers 0..10, got {channels!r}")
    if not np.isfinite(vref_plus) or not np.isfinite(vref_minus):
        raise NonFiniteError("vref_plus/vref_minus must be finite")
    if not vref_plus > vref_minus:
        raise InvalidArgument(f"vref_plus ({vref_plus}) must be above vref_minus ({vref_minus})")
    bad_rows = np.flatnonzero(~np.all(np.isfinite(v), axis=1))
    if bad_rows.size:
        raise NonFiniteError(f"volts: row {int(bad_rows[0])} holds NaN or Inf", index=int(bad_rows[0]))
    twin = CTwin(vref_plus=vref_plus, vref_minus=vref_minus, stuck_eoc=stuck_eoc,
                 stuck_dout=stuck_dout, trace_capacity=0, precision=precision)
    drv = Tlc2543(twin, length=length, lsb_first=lsb_first, bipolar=bipolar,
                  eoc_polls=eoc_polls, precision=precision)
    ffi, lib = drv._ffi, drv._lib
    cbuf = ffi.new("uint8_t[]", chans)
    done = ffi.new("size_t *")

    def step(row: int, m: int, first: bool, out: np.ndarray) -> tuple[int, int]:
        st = lib.tlc2543m_convert(twin._m, drv._dev, cbuf, k, ffi.cast("double *", v[row:row + m].ctypes.data), m,
                                  ffi.cast("int32_t *", out[row:].ctypes.data), 1 if (self_test and first) else 0,
                                  done)
        return int(st), int(done[0])

    return convert_in_chunks(n, k, chunk, step, lambda st: drv._after(st, "tlc2543 convert"), progress)
