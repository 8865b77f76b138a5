"""What a C callback sees as ``ctx`` when a C driver drives a Python device
model through extern "Python" callbacks (attitude_c.tlc2543,
attitude_c.ad7927): the model plus the first exception raised inside a
callback. Exceptions cannot cross C frames, so they are kept here and
re-raised once the C call returns. Also the pin callbacks themselves:
:func:`def_pin_callbacks`, :func:`connect_pins`."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Callable


class Bridge:
    """The model behind a set of C callbacks, and the first error they met."""

    def __init__(self, model: Any) -> None:
        self.model = model
        self.error: BaseException | None = None

    def call(self, name: str, *args: Any) -> Any:
        """``model.name(*args)``; after an error, 0 without calling (the C
        driver is already off the rails: stay quiet until it returns)."""
        if self.error is not None:
            return 0
        try:
            r = getattr(self.model, name)(*args)
        except BaseException as exc:  # noqa: BLE001 - re-raised by raise_pending()
            self.error = exc
            return 0
        return r if r is not None else 0

    def raise_pending(self) -> None:
        if self.error is not None:
            exc, self.error = self.error, None
            raise exc


def def_pin_callbacks(ffi: Any, prefix: str, setters: Sequence[str], getters: Sequence[str]) -> None:
    """Define the extern "Python" callbacks ``<prefix><name>`` (declared in
    csrc/cffi/<device>.cdef) as ``bridge.call(name, ...)`` on the Bridge behind
    ``ctx``: each setter ``(ctx, value) -> None`` (a pin level, or ns for
    ``delay_ns``), each getter ``(ctx) -> 1 or 0`` (a pin level)."""
    for name in setters:
        ffi.def_extern(name=prefix + name)(_setter(ffi, name))
    for name in getters:
        ffi.def_extern(name=prefix + name)(_getter(ffi, name))


def _setter(ffi: Any, name: str) -> Callable[[Any, int], None]:
    def callback(ctx: Any, value: int) -> None:
        ffi.from_handle(ctx).call(name, value)
    return callback


def _getter(ffi: Any, name: str) -> Callable[[Any], int]:
    def callback(ctx: Any) -> int:
        return 1 if ffi.from_handle(ctx).call(name) == 1 else 0
    return callback


def connect_pins(hal: Any, lib: Any, prefix: str, names: Sequence[str]) -> None:
    """Point each function field ``name`` of the C struct ``hal`` at the callback ``<prefix><name>``."""
    for name in names:
        setattr(hal, name, getattr(lib, prefix + name))
