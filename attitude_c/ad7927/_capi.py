"""CFFI plumbing: the C driver's HAL pointed at a Python model (extern
"Python" callbacks, pin level or frame level) or at the C twin
(csrc/host/ad7927_model.c), and the C status codes read from the library."""

from __future__ import annotations

from typing import Any

from .._bridge import Bridge, connect_pins, def_pin_callbacks
from .._lib import ffi_lib
from ..errors import DeviceError
from ._errors import AddressMismatch, FrameError
from .model import Frame, ProtocolViolation

__all__ = [
    "STATUS",
    "Bridge",
    "frame_log",
    "python_hal",
    "register",
]

_registered: set[str] = set()
#: the pin callbacks ad7927py_<name> (csrc/cffi/ad7927.cdef), each calling the model's method <name>
_SETTERS = ("set_cs", "set_sclk", "set_din", "delay_ns")
_GETTERS = ("get_dout",)


def register(precision: str) -> tuple[Any, Any]:
    """(ffi, lib) with the Python callbacks registered."""
    ffi, lib = ffi_lib(precision)
    if precision in _registered:
        return ffi, lib
    def_pin_callbacks(ffi, "ad7927py_", _SETTERS, _GETTERS)

    @ffi.def_extern(name="ad7927py_transfer")
    def _transfer(ctx: Any, tx: Any, rx: Any, n: int, hold_ns: int) -> int:
        bridge = ffi.from_handle(ctx)
        out = bridge.call("transfer", [tx[i] for i in range(n)], hold_ns)
        if bridge.error is not None:
            return -1
        for i in range(n):
            rx[i] = out[i]
        return 0

    _registered.add(precision)
    return ffi, lib


def python_hal(ffi: Any, lib: Any, bridge: Bridge, frames: bool) -> tuple[Any, Any, Any]:
    """An ad7927_hal reaching ``bridge.model``: frame level (the model's
    ``transfer``) or pin level (ad7927_pins_transfer over pin callbacks).
    Returns (hal, pins, handle); keep all three alive while the driver runs."""
    handle = ffi.new_handle(bridge)
    hal = ffi.new("ad7927_hal *")
    if frames:
        hal.ctx = handle
        hal.transfer = lib.ad7927py_transfer
        return hal, None, handle
    pins = ffi.new("ad7927_pins *")
    pins.ctx = handle
    connect_pins(pins, lib, "ad7927py_", _SETTERS + _GETTERS)
    hal.ctx = pins
    hal.transfer = ffi.addressof(lib, "ad7927_pins_transfer")
    return hal, pins, handle


#: The driver's and its model's status codes (attitude/ad7927.h, csrc/host/ad7927_model.h),
#: keyed by C name (attitude_c.names) -> (class, text).
STATUS: dict[str, tuple[type[Exception], str]] = {
    "AD7927_E_CHANNEL": (AddressMismatch, ("an output word names another channel "
                                           "than the one written for that frame")),
    "AD7927_E_FRAME": (FrameError, ("an output word's leading bit is 1 (DOUT stuck "
                                    "high or no part on the bus?)")),
    "AD7927_E_TRANSFER": (DeviceError, "the frame-transfer HAL failed"),
    "AD7927M_E_VIOLATION": (ProtocolViolation, "protocol violation"),
}


def frame_log(m: Any) -> list[Frame]:
    return [Frame(int(f.t), int(f.din), int(f.dout), int(f.channel), bool(f.valid))
            for f in (m.frames[i] for i in range(m.frames_len))]
