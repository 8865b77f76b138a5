"""Exceptions of attitude_c.

One base class, :class:`AttitudeError`, mixed with the builtin exception a
user would naturally catch (pynacl style): a bad argument is both an
``AttitudeError`` and a ``ValueError``; a device timeout is also a
``TimeoutError``; and so on. Which exception a C status code raises is
:func:`attitude_c.names.raise_for_status`'s (the codes are read from the
library there; this module imports nothing of the package).
"""

from __future__ import annotations


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
    """A value lies outside its documented range (a fixed-point format, the
    integrator's |Δθ| ≤ π per sample, an overflowing result); ``index`` names
    the first bad sample when the input has samples."""

    def __init__(self, message: str, index: int | None = None) -> None:
        super().__init__(message)
        self.index = index


class DeviceError(AttitudeError, RuntimeError):
    """A (modelled) device misbehaved: self-test failure, protocol violation."""


class DeviceTimeout(AttitudeError, TimeoutError):
    """A bounded wait on a device expired (e.g. TLC2543 EOC stuck)."""


class LinkError(AttitudeError, OSError):
    """The serial link failed (port missing, dead line, gave up)."""


class LinkBusy(LinkError):
    """A link sender was given a block while the previous one is still in progress."""


class BlockFormatError(InvalidArgument):
    """A record breaks the block format (csrc/include/attitude/block.h).

    ``status`` is the C status (``lib.ATT_BLOCK_E_*``), ``index`` the
    position of the record in its stream when known.
    """

    def __init__(self, message: str, status: int, index: int | None = None) -> None:
        super().__init__(message)
        self.status = status
        self.index = index
