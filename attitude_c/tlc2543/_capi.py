"""CFFI plumbing: the C driver's HAL pointed at a Python model (extern
"Python" callbacks) or at the C twin (csrc/host/tlc2543_model.c)."""

from __future__ import annotations

from typing import Any

from .._bridge import Bridge
from .._lib import ffi_lib

__all__ = ["Bridge", "python_hal", "register"]

_registered: set[str] = set()


def register(precision: str) -> tuple[Any, Any]:
    """(ffi, lib) with the Python pin callbacks registered."""
    ffi, lib = ffi_lib(precision)
    if precision in _registered:
        return ffi, lib

    @ffi.def_extern(name="tlc2543py_set_cs")
    def _set_cs(ctx: Any, level: int) -> None:
        ffi.from_handle(ctx).call("set_cs", level)

    @ffi.def_extern(name="tlc2543py_set_clock")
    def _set_clock(ctx: Any, level: int) -> None:
        ffi.from_handle(ctx).call("set_clock", level)

    @ffi.def_extern(name="tlc2543py_set_din")
    def _set_din(ctx: Any, level: int) -> None:
        ffi.from_handle(ctx).call("set_din", level)

    @ffi.def_extern(name="tlc2543py_get_dout")
    def _get_dout(ctx: Any) -> int:
        return 1 if ffi.from_handle(ctx).call("get_dout") == 1 else 0

    @ffi.def_extern(name="tlc2543py_get_eoc")
    def _get_eoc(ctx: Any) -> int:
        return 1 if ffi.from_handle(ctx).call("get_eoc") == 1 else 0

    @ffi.def_extern(name="tlc2543py_delay_ns")
    def _delay_ns(ctx: Any, ns: int) -> None:
        ffi.from_handle(ctx).call("delay_ns", ns)

    _registered.add(precision)
    return ffi, lib


def python_hal(ffi: Any, lib: Any, bridge: Bridge) -> tuple[Any, Any]:
    """A tlc2543_hal whose callbacks reach ``bridge.model``; returns
    (hal, handle) — keep both alive as long as the driver uses them."""
    handle = ffi.new_handle(bridge)
    hal = ffi.new("tlc2543_hal *")
    hal.ctx = handle
    hal.set_cs = lib.tlc2543py_set_cs
    hal.set_clock = lib.tlc2543py_set_clock
    hal.set_din = lib.tlc2543py_set_din
    hal.get_dout = lib.tlc2543py_get_dout
    hal.get_eoc = lib.tlc2543py_get_eoc
    hal.delay_ns = lib.tlc2543py_delay_ns
    return hal, handle
