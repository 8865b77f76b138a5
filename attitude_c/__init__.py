"""attitude_c — Python side of libattitude.

Strapdown attitude measurement for small embedded systems: the C99
rotation-vector integrator (CFFI bindings), an independent NumPy
reference, device and channel models and the full-system simulator.

Conventions (quaternion scalar first, ENU navigation frame, z-x-y Euler
angles ordered [yaw, pitch, roll]) are in docs/conventions.md.
"""

from __future__ import annotations

from .errors import (
    AttitudeError,
    DeviceError,
    DeviceTimeout,
    InvalidArgument,
    InvalidType,
    LinkError,
    NonFiniteError,
    RangeError,
)

__version__ = "0.1.0"

__all__ = [
    "AttitudeError",
    "DeviceError",
    "DeviceTimeout",
    "InvalidArgument",
    "InvalidType",
    "LinkError",
    "NonFiniteError",
    "RangeError",
    "__version__",
]

# The integrator API (attitude_c.core) is re-exported here.
try:
    from .core import *  # noqa: F401,F403
    from .core import __all__ as _core_all

    __all__ += list(_core_all)
except ImportError as _exc:  # pragma: no cover - only while core is absent
    if "attitude_c.core" not in str(_exc) and "No module named" not in str(_exc):
        raise
