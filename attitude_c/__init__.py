"""attitude_c — Python side of libattitude.

Strapdown attitude measurement for small embedded systems: the C99
rotation-vector integrator (CFFI bindings), an independent NumPy
reference, device and channel models and the full-system simulator.

Conventions (quaternion scalar first, ENU navigation frame, z-x-y Euler
angles ordered [yaw, pitch, roll]) are in docs/conventions.md.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

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

#: libattitude's version "MAJOR.MINOR.PATCH", from the compiled library
#: (enums of csrc/include/attitude/version.h, its one source); read on first
#: access, so that importing the package still loads no C extension.
__version__: str

if not TYPE_CHECKING:
    def __getattr__(name: str) -> str:
        if name == "__version__":
            from ._lib import ffi_lib

            lib = ffi_lib("f64")[1]
            v = f"{lib.ATT_VERSION_MAJOR}.{lib.ATT_VERSION_MINOR}.{lib.ATT_VERSION_PATCH}"
            globals()["__version__"] = v
            return v
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

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

# The aiding solvers (docs/aiding.md): loading them loads no C extension either.
from . import magcal
from .aiding import align, align_static, gauss_newton, triad

__all__ += ["align", "align_static", "gauss_newton", "magcal", "triad"]

# The attitude filter (docs/ahrs.md): attitude_c.Ahrs (streaming), attitude_c.ahrs (batch).
from .ahrs_filter import Ahrs, ahrs

__all__ += ["Ahrs", "ahrs"]

# Aiding-sensor time alignment (docs/ahrs.md, "Sensor timing"): the magnetometer's lag behind the gyro.
from .timing import aiding_delay

__all__ += ["aiding_delay"]

# The UAV thesis's own EKF, for reproduction (docs/ahrs.md, "The thesis's EKF").
from .thesis_ekf import ahrs_thesis

__all__ += ["ahrs_thesis"]

# The MEMS AHRS paper's nine-state filter with GNSS-velocity aiding (docs/gnss-paper-filter.md).
from .gnss9 import Gnss9, ahrs_gnss9

__all__ += ["Gnss9", "ahrs_gnss9"]

# Noise identification (docs/noise.md): the Allan deviation of a rest recording, its noise terms
# and the filter settings they give (needs allantools: pip install 'attitude-c[noise]').
from .noise import allan

__all__ += ["allan"]
