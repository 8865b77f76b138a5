"""What a C callback sees as ``ctx`` when a C driver drives a Python device
model through extern "Python" callbacks (attitude_c.tlc2543,
attitude_c.ad7927): the model plus the first exception raised inside a
callback. Exceptions cannot cross C frames, so they are kept here and
re-raised once the C call returns."""

from __future__ import annotations

from typing import Any


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
