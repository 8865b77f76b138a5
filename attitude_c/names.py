"""Names and codes of libattitude, in one table keyed by their C names.

Every integer constant of the public headers — method numbers, status codes,
limits, block-format and fixed-point constants — is read from the compiled
library, never typed again in Python::

    from attitude_c.names import C
    C["ATT_FX_DTHETA_MAX"], C["ATT_BLOCK_E_CODE"], C["ATT_METHOD_RV3"]

:data:`STATUS` says, for each status code of the library (keyed by its C
name), which exception a Python caller gets and what the code means (the
library's own text, ``att_status_str``: :func:`status_text`);
:func:`raise_for_status` turns a
returned code into that exception. The method names come from the library
too (:func:`method_names`, ``att_integ_method_name``), and so does the
number of samples each method consumes per update (:func:`samples_per_update`,
``att_integ_outputs``). ``tests/test_names.py`` proves that this table and
the headers' enums agree, value for value.

The table is filled on first use: importing this module loads no C extension.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from functools import cache
from typing import Any, Literal, get_args

from .errors import (
    AttitudeError,
    BlockFormatError,
    DeviceTimeout,
    InvalidArgument,
    LinkBusy,
    LinkError,
    NonFiniteError,
    RangeError,
)

__all__ = [
    "INCREMENT_METHODS",
    "METHODS",
    "STATUS",
    "C",
    "Method",
    "method_code",
    "method_names",
    "raise_for_status",
    "samples_per_update",
    "status_name",
    "status_text",
]

#: Integration methods (the type checkers' view; ``METHODS`` is the same list at
#: run time; :mod:`attitude_c.core` re-exports them). The C enum value of each is the
#: library's ``ATT_METHOD_<NAME>`` constant (see :func:`method_code`), never a position
#: here; tests/test_names.py proves the list is the library's.
Method = Literal["rv1", "rv2", "rv3", "rv3-coning", "rv3-reuse", "rv3-reuse-poly", "rk4"]
METHODS: tuple[Method, ...] = get_args(Method)
#: Methods fed with angle increments (``integrate``); ``rk4`` takes rates.
INCREMENT_METHODS: tuple[Method, ...] = tuple(m for m in METHODS if m != "rk4")

#: Prefixes of the library's constants (the modules' prefixes, upper case).
PREFIXES = ("ATT_", "TLC2543", "AD7927")


def _ffi_lib() -> tuple[Any, Any]:
    from ._lib import ffi_lib

    return ffi_lib("f64")


def _lib() -> Any:
    return _ffi_lib()[1]


class _Constants(Mapping[str, int]):
    """Every integer constant of the compiled library, by C name (read once)."""

    _values: dict[str, int] | None = None

    def _table(self) -> dict[str, int]:
        if self._values is None:
            lib = _lib()
            out: dict[str, int] = {}
            for name in dir(lib):
                if name.startswith(PREFIXES):
                    v = getattr(lib, name)
                    if isinstance(v, int):
                        out[name] = v
            type(self)._values = out
        assert self._values is not None
        return self._values

    def __getitem__(self, name: str) -> int:
        try:
            return self._table()[name]
        except KeyError:
            raise KeyError(f"libattitude has no constant {name!r}") from None

    def __iter__(self) -> Iterator[str]:
        return iter(self._table())

    def __len__(self) -> int:
        return len(self._table())

    def __repr__(self) -> str:
        return f"<libattitude constants: {len(self)} names>"


#: The library's constants, keyed by C name (``C["ATT_E_ARG"] == -2``).
C: Mapping[str, int] = _Constants()

# The exception a Python caller gets for each status code, by C name. The text
# of a code is the library's own (att_status_str, csrc/src/common.c: one table
# for every module). The device drivers and their models (attitude_c.tlc2543,
# attitude_c.ad7927: their own exception classes) and the denoiser (texts
# naming its choices) give the meanings of their codes in their own modules,
# keyed by C name too, through raise_for_status's ``extra``.
_CLASSES: dict[str, type[Exception]] = {
    # generic (common.h)
    "ATT_E_NULL": InvalidArgument,
    "ATT_E_ARG": InvalidArgument,
    "ATT_E_NONFINITE": NonFiniteError,
    "ATT_E_RANGE": RangeError,
    "ATT_E_STATE": AttitudeError,
    "ATT_E_TIMEOUT": DeviceTimeout,
    "ATT_E_BUFFER": InvalidArgument,
    # integrator.h
    "ATT_E_INTEG_METHOD": InvalidArgument,
    "ATT_E_INTEG_DIVERGED": RangeError,
    "ATT_E_INTEG_RANGE": RangeError,
    # link.h, link2.h
    "ATT_LINK_E_NULL": InvalidArgument,
    "ATT_LINK_E_CONFIG": InvalidArgument,
    "ATT_LINK_E_BUSY": LinkBusy,
    "ATT_LINK_E_STATE": LinkError,
    "ATT_LINK2_E_NULL": InvalidArgument,
    "ATT_LINK2_E_CONFIG": InvalidArgument,
    "ATT_LINK2_E_FULL": LinkBusy,
    "ATT_LINK2_E_STATE": LinkError,
    # gnss.h
    "ATT_GNSS_E_NULL": InvalidArgument,
    "ATT_GNSS_E_STATE": AttitudeError,
    # fixed.h
    "ATT_FX_E_RANGE": RangeError,
    "ATT_FX_E_METHOD": InvalidArgument,
    "ATT_FX_E_ZERO": InvalidArgument,
    # ahrs.h
    "ATT_E_AHRS_DT": InvalidArgument,
    "ATT_E_AHRS_UNITS": InvalidArgument,
    "ATT_E_AHRS_SETTINGS": InvalidArgument,
    "ATT_E_AHRS_DIVERGED": RangeError,
    "ATT_E_AHRS_ALIGN": AttitudeError,
    # ahrs_thesis.h
    "ATT_E_TEKF_DT": InvalidArgument,
    "ATT_E_TEKF_SETTINGS": InvalidArgument,
    "ATT_E_TEKF_DIVERGED": RangeError,
    "ATT_E_TEKF_ALIGN": AttitudeError,
    # ahrs_gnss9.h
    "ATT_E_G9_DT": InvalidArgument,
    "ATT_E_G9_SETTINGS": InvalidArgument,
    "ATT_E_G9_DIVERGED": RangeError,
    "ATT_E_G9_ALIGN": AttitudeError,
    "ATT_E_G9_AGE": InvalidArgument,
    # block.h
    "ATT_BLOCK_E_CODE": BlockFormatError,
    "ATT_BLOCK_E_KIND": BlockFormatError,
    "ATT_BLOCK_E_FIELD": BlockFormatError,
    "ATT_BLOCK_E_SEQ": BlockFormatError,
    # aiding.h
    "ATT_AID_E_ZERO_F": InvalidArgument,
    "ATT_AID_E_ZERO_M": InvalidArgument,
    "ATT_AID_E_PARALLEL": InvalidArgument,
    "ATT_AID_E_MOVING": InvalidArgument,
    "ATT_AID_E_FEW": InvalidArgument,
    "ATT_AID_E_SINGULAR": RangeError,
    "ATT_AID_E_NOCONV": RangeError,
    "ATT_AID_E_SPAN": InvalidArgument,
    "ATT_AID_E_FIT": InvalidArgument,
}


def status_text(status: int) -> str:
    """The library's description of status code ``status`` (``att_status_str``;
    the host device twins' own codes: ``devm_status_str``, csrc/host/devmodel.h;
    "unknown status" for a value no header defines)."""
    ffi, lib = _ffi_lib()
    return str(ffi.string(lib.devm_status_str(int(status))).decode())


class _Status(Mapping[str, tuple[type[Exception], str]]):
    """C name -> (exception class, the library's text), read on first use."""

    def __getitem__(self, name: str) -> tuple[type[Exception], str]:
        return _CLASSES[name], status_text(C[name])

    def __iter__(self) -> Iterator[str]:
        return iter(_CLASSES)

    def __len__(self) -> int:
        return len(_CLASSES)

    def __repr__(self) -> str:
        return f"<libattitude status meanings: {len(self)} codes>"


#: What each status code of the library means to a Python caller, keyed by its C
#: name: (exception class, ``att_status_str`` text).
STATUS: Mapping[str, tuple[type[Exception], str]] = _Status()


@cache
def _status_names() -> dict[int, str]:
    """Status value -> C name: the negative constants named ``*_E_*``."""
    out: dict[int, str] = {}
    for name, v in C.items():
        if v < 0 and "_E_" in name:
            out.setdefault(v, name)
    return out


def status_name(status: int) -> str | None:
    """The C name of status code ``status`` (``-2`` -> ``"ATT_E_ARG"``), None if unknown."""
    return _status_names().get(int(status))


def raise_for_status(status: int, what: str,
                     extra: Mapping[str, tuple[type[Exception], str]] | None = None,
                     index: int | None = None) -> None:
    """Raise the exception of C status ``status`` (no-op for ``ATT_OK`` and results >= 0).

    ``what`` names the call or argument; ``index``, when given, the sample
    (message "... at sample i", and ``NonFiniteError.index``); ``extra``
    maps C names to (exception class, text) for a module's own meanings."""
    if status >= 0:
        return
    name = status_name(status)
    meaning = None
    if name is not None:
        meaning = (extra or {}).get(name) or STATUS.get(name)
    cls, text = meaning or (AttitudeError, status_text(status))  # the library's text, whatever the module
    where = f" at sample {index}" if index is not None else ""
    msg = f"{what}: {text}{where} (status {status}{', ' + name if name else ''})"
    if issubclass(cls, (NonFiniteError, RangeError)):
        raise cls(msg, index=index)
    if issubclass(cls, BlockFormatError):
        raise cls(msg, status, index)
    raise cls(msg)


@cache
def method_names() -> tuple[str, ...]:
    """The integration methods' names in ``att_method`` order (``att_integ_method_name``)."""
    from ._lib import ffi_lib

    ffi, lib = ffi_lib("f64")
    return tuple(ffi.string(lib.att_integ_method_name(i)).decode() for i in range(lib.ATT_METHOD_COUNT))


def method_code(method: str) -> int:
    """The ``att_method`` value of ``method`` ("rv3-reuse" -> ``ATT_METHOD_RV3_REUSE``)."""
    try:
        return method_names().index(method)
    except ValueError:
        raise InvalidArgument(f"method must be one of {method_names()!r}, got {method!r}") from None


@cache
def samples_per_update(method: str) -> int:
    """Increments (rk4: rate rows) ``method`` consumes per attitude update once
    running, from the library's own count (``att_integ_outputs``): 1 for rv1 and
    the reuse forms, 2 for rv2 and rk4 (the step's midpoint and end rows), 3 for
    rv3 and rv3-coning."""
    from ._lib import ffi_lib

    ffi, lib = ffi_lib("f64")
    s = ffi.new("att_integ *")
    if lib.att_integ_init(s, method_code(method), ffi.NULL) != 0:
        raise InvalidArgument(f"unknown method {method!r}")
    big = 6 * 7 * 1000
    return big // int(lib.att_integ_outputs(s, big + 1) - lib.att_integ_outputs(s, 1))
