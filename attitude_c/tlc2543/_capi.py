"""CFFI plumbing: the C driver's HAL pointed at a Python model (extern
"Python" callbacks) or at the C twin (csrc/host/tlc2543_model.c)."""

from __future__ import annotations

from typing import Any

from .._bridge import Bridge, connect_pins, def_pin_callbacks
from .._lib import ffi_lib

__all__ = ["Bridge", "python_hal", "register"]

_registered: set[str] = set()
#: the pin callbacks tlc2543py_<name> (csrc/cffi/tlc2543.cdef), each calling the model's method <name>
_SETTERS = ("set_cs", "set_clock", "set_din", "delay_ns")
_GETTERS = ("get_dout", "get_eoc")


def register(precision: str) -> tuple[Any, Any]:
    """(ffi, lib) with the Python pin callbacks registered."""
    ffi, lib = ffi_lib(precision)
    if precision not in _registered:
        def_pin_callbacks(ffi, "tlc2543py_", _SETTERS, _GETTERS)
        _registered.add(precision)
    return ffi, lib


def python_hal(ffi: Any, lib: Any, bridge: Bridge) -> tuple[Any, Any]:
    """A tlc2543_hal whose callbacks reach ``bridge.model``; returns
    (hal, handle) — keep both alive as long as the driver uses them."""
    handle = ffi.new_handle(bridge)
    hal = ffi.new("tlc2543_hal *")
    hal.ctx = handle
    connect_pins(hal, lib, "tlc2543py_", _SETTERS + _GETTERS)
    return hal, handle
