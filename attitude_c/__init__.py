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

# The integrator API (attitude_c.core) is re-exported here. Importing it does
# not load the C extension (attitude_c._lib loads it on first use).
from . import core as _core
from .core import *

__all__ += list(_core.__all__)
