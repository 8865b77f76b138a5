"""Errors of the AD7927 drivers (the C driver's AD7927_E_* codes and the
reference driver raise the same classes)."""

from __future__ import annotations

from ..errors import DeviceError


class AddressMismatch(DeviceError):
    """An output word names another channel than the one written for that
    frame (AD7927_E_CHANNEL): a missed control write, a wrong address, a
    stuck DOUT line. ``word`` is the 16-bit word, ``expected`` the channel."""

    def __init__(self, message: str, word: int | None = None, expected: int | None = None) -> None:
        super().__init__(message)
        self.word = word
        self.expected = expected


class FrameError(DeviceError):
    """An output word's leading bit is 1 (AD7927_E_FRAME): DOUT stuck high,
    no part on the bus. ``word`` is the 16-bit word."""

    def __init__(self, message: str, word: int | None = None, expected: int | None = None) -> None:
        super().__init__(message)
        self.word = word
        self.expected = expected
