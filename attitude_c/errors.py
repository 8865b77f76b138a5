"""Exceptions of attitude_c.

One base class, :class:`AttitudeError`, mixed with the builtin exception a
user would naturally catch (pynacl style): a bad argument is both an
``AttitudeError`` and a ``ValueError``; a device timeout is also a
``TimeoutError``; and so on.
"""

from __future__ import annotations

from collections.abc import Mapping


class AttitudeError(Exception):
    """Base class of every error raised by attitude_c."""


class InvalidArgument(AttitudeError, ValueError):
    """An argument has the wrong value or shape."""


class InvalidType(AttitudeError, TypeError):
    """An argument has the wrong type or dtype."""


class NonFiniteError(InvalidArgument):
    """An input array holds NaN or Inf; ``index`` names the first bad sample."""

    def __init__(self, message: str, index: int | None = None) -> None:
        super().__init__(message)
        self.index = index


class RangeError(InvalidArgument):
    """A value lies outside the representable range (e.g. a fixed-point format)."""


class DeviceError(AttitudeError, RuntimeError):
    """A (modelled) device misbehaved: self-test failure, protocol violation."""


class DeviceTimeout(AttitudeError, TimeoutError):
    """A bounded wait on a device expired (e.g. TLC2543 EOC stuck)."""


class LinkError(AttitudeError, OSError):
    """The serial link failed (port missing, dead line, gave up)."""


class BlockFormatError(InvalidArgument):
    """A record breaks the block format (csrc/include/attitude/block.h).

    ``status`` is the C status (``lib.ATT_BLOCK_E_*``), ``index`` the
    position of the record in its stream when known.
    """

    def __init__(self, message: str, status: int, index: int | None = None) -> None:
        super().__init__(message)
        self.status = status
        self.index = index


# C status codes of csrc/include/attitude/common.h (generic range).
_GENERIC = {
    -1: (InvalidArgument, "NULL pointer argument"),
    -2: (InvalidArgument, "argument out of range"),
    -3: (NonFiniteError, "non-finite input (NaN or Inf)"),
    -4: (RangeError, "value outside representable range"),
    -5: (AttitudeError, "call not valid in current state"),
    -6: (DeviceTimeout, "timeout"),
    -7: (InvalidArgument, "buffer too small"),
}


def raise_for_status(status: int, what: str, extra: Mapping[int, tuple[type[Exception], str]] | None = None) -> None:
    """Raise the exception matching C status ``status`` (no-op for ATT_OK).

    ``what`` names the call or argument, so the message says what failed.
    ``extra`` maps module-specific codes to (exception class, text).
    """
    if status >= 0:
        return
    table: dict[int, tuple[type[Exception], str]] = dict(_GENERIC)
    if extra:
        table.update(extra)
    cls, text = table.get(status, (AttitudeError, f"unknown status {status}"))
    raise cls(f"{what}: {text} (status {status})")
