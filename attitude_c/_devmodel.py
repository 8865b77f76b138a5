"""Pieces shared by the ADC packages (attitude_c.tlc2543, attitude_c.ad7927):
their device models' argument checks, the C twins' violation and trace
read-out, the model's error raised after a driver call, and the chunked
batch conversion through a C driver."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Callable, Generic, NoReturn, TypeVar

import numpy as np

from .errors import DeviceError, InvalidArgument, NonFiniteError


class ProtocolViolationBase(DeviceError):
    """A driver broke a device's protocol or timing rule (each device model
    subclasses it with its ``device`` name). ``rule`` names the rule (one of
    the model's RULES); ``time_ns`` is the model time."""

    device = "device"

    def __init__(self, rule: str, message: str, time_ns: int) -> None:
        super().__init__(f"{self.device} protocol violation [{rule}] at t={time_ns} ns: {message}")
        self.rule = rule
        self.time_ns = time_ns


class PinModel:
    """What the pin-level device models share: the first-violation raise,
    the trace log and the DOUT pin (with its stuck-at fault). Subclasses set
    ``violation`` and keep ``t``, ``record``, ``trace``, ``stuck_dout`` and
    ``dout_level``."""

    violation: type[ProtocolViolationBase] = ProtocolViolationBase
    HIGH_Z = 2  #: DOUT value in the trace while it is not driven
    t: int
    record: bool
    trace: list[tuple[int, str, int]]
    stuck_dout: int | None
    dout_level: int

    def _fail(self, rule: str, message: str) -> NoReturn:
        raise self.violation(rule, message, self.t)

    def _log(self, signal: str, value: int) -> None:
        if self.record:
            self.trace.append((self.t, signal, value))

    def _set_dout(self, level: int) -> None:
        if self.stuck_dout is not None and level != self.HIGH_Z:
            level = self.stuck_dout
        if level != self.dout_level:
            self.dout_level = level
            self._log("DOUT", level)


def check_inputs(inputs: Sequence[float] | np.ndarray, count: int, pin: str) -> np.ndarray:
    """Input voltages as a contiguous float array of at most ``count``
    values; ``pin`` names the inputs in messages (``AIN``, ``VIN``)."""
    v = np.ascontiguousarray(np.asarray(inputs, dtype=float).reshape(-1))
    if v.size > count:
        raise InvalidArgument(f"inputs: at most {count} channels ({pin}0..{pin}{count - 1}), got {v.size}")
    if not np.all(np.isfinite(v)):
        bad = int(np.flatnonzero(~np.isfinite(v))[0])
        raise NonFiniteError(f"inputs: {pin}{bad} is not finite ({v[bad]})", index=bad)
    return v


def check_level(name: str, v: int | None) -> int:
    """A fault-injection level: None (-1 for the C twin), 0 or 1."""
    if v is None:
        return -1
    if isinstance(v, float) or v not in (0, 1):
        raise InvalidArgument(f"{name} must be None, 0 or 1, got {v!r}")
    return int(v)


def twin_violation(ffi: Any, m: Any, rules: Sequence[str], exc: type[Exception]) -> Exception | None:
    """A C twin's latched violation (``m.violation``, 1-based into ``rules``)
    as ``exc(rule, message, time_ns)``, or None."""
    if m.violation == 0:
        return None
    return exc(rules[m.violation - 1], ffi.string(m.message).decode(), int(m.violation_t))


def twin_trace(m: Any, signals: Sequence[str]) -> list[tuple[int, str, int]]:
    """A C twin's pin trace as (t_ns, signal name, value) tuples."""
    return [(int(m.trace[i].t), signals[m.trace[i].signal], int(m.trace[i].value))
            for i in range(m.trace_len)]


V = TypeVar("V", bound=Exception)


class CTwinBase(Generic[V]):
    """What the device models' C twins share: their analog inputs, pin trace,
    conversion count, model time and latched violation (an exception of type
    ``V``). A subclass sets ``_ffi``, ``_lib`` and ``_m`` (the C model) in its
    constructor and the class attributes below."""

    #: the twin's ``<model>_set_inputs(m, const double *v, n)``, the number of inputs and their pin name
    _SET_INPUTS: tuple[str, int, str]
    _SIGNALS: Sequence[str]     #: the trace's signal names
    _RULES: Sequence[str]       #: the protocol rules (``m.violation`` is 1-based into them)
    _VIOLATION: type[V]         #: the exception a latched violation becomes
    _ffi: Any
    _lib: Any
    _m: Any

    def set_inputs(self, inputs: Sequence[float] | np.ndarray) -> None:
        from .names import raise_for_status

        fn, count, pin = self._SET_INPUTS
        v = check_inputs(inputs, count, pin)
        st = getattr(self._lib, fn)(self._m, self._ffi.cast("double *", v.ctypes.data), v.size)
        raise_for_status(st, "CTwin.set_inputs(inputs)")

    @property
    def trace(self) -> list[tuple[int, str, int]]:
        return twin_trace(self._m, self._SIGNALS)

    @property
    def conversions(self) -> int:
        return int(self._m.conversions)

    @property
    def t(self) -> int:
        return int(self._m.t)

    def violation(self) -> V | None:
        """The latched violation (or None)."""
        return twin_violation(self._ffi, self._m, self._RULES, self._VIOLATION)  # type: ignore[return-value]


def raise_model_error(bridge: Any, model: Any) -> None:
    """After a C driver call: re-raise the exception a Python model's callback
    met (``bridge``, an attitude_c._bridge.Bridge), or else raise the violation
    the C twin ``model`` latched; nothing when there is none."""
    if bridge is not None:
        bridge.raise_pending()
    elif isinstance(model, CTwinBase):
        v = model.violation()
        if v is not None:
            raise v


def convert_in_chunks(n: int, k: int, chunk: int, step: Callable[[int, int, bool, np.ndarray], tuple[int, int]],
                      after: Callable[[int], None], progress: Callable[[int], None] | None) -> np.ndarray:
    """Run a C batch conversion over ``n`` rows of ``k`` columns, ``chunk``
    rows per call: ``step(row, m, first, out)`` converts rows row..row+m-1
    into ``out`` (int32, (n, k)) and returns (status, rows done);
    ``after(status)`` raises the matching error, which gets ``codes`` (the
    rows done) and ``rows_done`` attached. ``progress(rows_done)`` after
    each call. The first call runs even for n = 0 (it may do set-up work)."""
    if isinstance(chunk, bool) or not isinstance(chunk, (int, np.integer)) or chunk < 1:
        raise InvalidArgument(f"chunk must be a positive int, got {chunk!r}")
    out = np.zeros((n, k), dtype=np.int32)
    row, first = 0, True
    while first or row < n:
        m = min(int(chunk), n - row)
        st, done = step(row, m, first, out)
        first = False
        row += done
        if st != 0:
            try:
                after(st)
            except Exception as exc:  # attach what was converted before the error
                exc.codes = out[:row].astype(np.int64)  # type: ignore[attr-defined]
                exc.rows_done = row  # type: ignore[attr-defined]
                raise
        if progress is not None and m:
            progress(row)
        if m == 0:
            break
    return out.astype(np.int64)
