"""Settings structs of the C filters, read and filled by name.

One helper for every ``att_<module>_settings`` struct (the attitude filter's,
the thesis EKF's): the setting names, their kinds and their defaults come
from the compiled library — the struct's fields as CFFI reads them from the
header, and its ``*_default_settings`` function — so a field added to the
header is a keyword setting without a change here. A Python caller gives the
settings as keywords named as the fields; each is checked by name:

* unknown name → :class:`~attitude_c.errors.InvalidArgument` listing the known ones;
* wrong type → :class:`~attitude_c.errors.InvalidType` (a real field takes a
  real number, an integer field an integer; ``bool`` is neither);
* not finite, or outside the C type's range → ``InvalidArgument``;
* outside the documented domain (the library's ``*_check_settings``) →
  ``InvalidArgument`` naming the setting: the one the library names when it can
  (``SettingsSpec.field_fn``, e.g. ``att_ahrs_check_settings_field``: the first
  field outside its domain), else those that fail on their own.

Commands take a setting as ``NAME=VALUE`` text (``attitude ahrs --set``,
``simulate --ahrs-setting``, ``view --ahrs-setting``): :func:`parse_assignment`
is the one parser of that text for every command.

A struct may expose an integer field by name (``Choice``: the filter's
``method`` as ``"rv3-reuse"``) and fields of a nested struct under
``<outer>_<inner>`` (the thesis EKF's ``gn_max_iter``).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cache
from typing import Any, Callable, Literal

import numpy as np

from ._options import OptionError
from ._validate import C_INT_RANGES as _INT_RANGES
from ._validate import integer, real
from .errors import InvalidArgument

__all__ = ["Choice", "SettingNames", "SettingsSpec", "defaults", "fill", "kinds", "parse_assignment", "read"]

Kind = Literal["real", "int", "choice"]

@dataclass(frozen=True)
class Choice:
    """An integer field given by name: ``encode(setting, value) -> int`` (raises
    InvalidArgument / InvalidType naming ``setting``), ``decode(int) -> value``."""

    encode: Callable[[str, Any], int]
    decode: Callable[[int], Any]


@dataclass(frozen=True, eq=False)
class SettingsSpec:
    """A C settings struct: its type, default and check functions (names in the
    library), what the messages call it, and how some fields are exposed."""

    ctype: str                 #: "att_ahrs_settings"
    default_fn: str            #: "att_ahrs_default_settings" (fills the struct)
    check_fn: str              #: "att_ahrs_check_settings" (ATT_OK or a *_SETTINGS status)
    label: str                 #: in "unknown <label> setting 'x'"
    domain: str                #: the documented domain, quoted by the domain error
    choices: Mapping[str, Choice] = field(default_factory=dict)
    #: nested struct field -> its fields exposed as "<outer>_<inner>" (others stay at their defaults)
    nested: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    #: "att_ahrs_check_settings_field": the check that also names the failing field (None: the
    #: settings are re-checked one by one to name it)
    field_fn: str | None = None


def _kind_of(ctype: Any) -> str | None:
    if ctype.kind != "primitive":
        return None
    if ctype.cname in ("float", "double"):
        return "real"
    if ctype.cname in _INT_RANGES:
        return ctype.cname
    return None


@cache
def _fields(spec: SettingsSpec) -> dict[str, tuple[tuple[str, ...], str]]:
    """Setting name -> (field path, kind): ``kind`` "real", "choice" or the C integer type name."""
    from ._lib import ffi_lib

    ffi = ffi_lib("f64")[0]
    out: dict[str, tuple[tuple[str, ...], str]] = {}
    for name, f in ffi.typeof(spec.ctype).fields:
        if f.type.kind == "struct" and name in spec.nested:
            inner = dict(f.type.fields)
            for sub in spec.nested[name]:
                kind = _kind_of(inner[sub].type)
                if kind is None:
                    raise TypeError(f"{spec.ctype}.{name}.{sub}: not a number field")  # pragma: no cover
                out[f"{name}_{sub}"] = ((name, sub), kind)
            continue
        kind = "choice" if name in spec.choices else _kind_of(f.type)
        if kind is not None:
            out[name] = ((name,), kind)
    return out


def kinds(spec: SettingsSpec) -> dict[str, Kind]:
    """Setting name -> "real", "int" or "choice", in the struct's order."""
    return {k: ("real" if kind == "real" else "choice" if kind == "choice" else "int")
            for k, (_, kind) in _fields(spec).items()}


class SettingNames(Sequence[str]):
    """The names of one kind of setting of a struct, read from the library on first use
    (so that importing a module that defines one loads no C extension)."""

    def __init__(self, spec: SettingsSpec, kind: Kind | None = None) -> None:
        self._spec = spec
        self._kind = kind

    def _names(self) -> tuple[str, ...]:
        return tuple(k for k, v in kinds(self._spec).items() if self._kind is None or v == self._kind)

    def __getitem__(self, i: Any) -> Any:
        return self._names()[i]

    def __len__(self) -> int:
        return len(self._names())

    def __iter__(self) -> Iterator[str]:
        return iter(self._names())

    def __contains__(self, name: object) -> bool:
        return name in self._names()

    def __eq__(self, other: object) -> bool:
        if isinstance(other, (SettingNames, tuple, list)):
            return tuple(self) == tuple(other)
        return NotImplemented

    def __hash__(self) -> int:
        return hash(self._names())

    def __repr__(self) -> str:
        return repr(self._names())


def _get(s: Any, path: tuple[str, ...]) -> Any:
    for p in path:
        s = getattr(s, p)
    return s


def _set(s: Any, path: tuple[str, ...], value: Any) -> None:
    for p in path[:-1]:
        s = getattr(s, p)
    setattr(s, path[-1], value)


def read(spec: SettingsSpec, s: Any) -> dict[str, Any]:
    """A filled struct ``s`` as a dict (choices by name, reals as float, integers as int)."""
    out: dict[str, Any] = {}
    for k, (path, kind) in _fields(spec).items():
        v = _get(s, path)
        out[k] = spec.choices[k].decode(int(v)) if kind == "choice" else float(v) if kind == "real" else int(v)
    return out


def defaults(spec: SettingsSpec) -> dict[str, Any]:
    """The library's defaults (``spec.default_fn``) as a dict."""
    from ._lib import ffi_lib

    ffi, lib = ffi_lib("f64")
    s = ffi.new(f"{spec.ctype} *")
    getattr(lib, spec.default_fn)(s)
    return read(spec, s)


def _value(spec: SettingsSpec, name: str, kind: str, v: Any) -> Any:
    """``v`` checked for setting ``name`` of ``kind``, as the C field takes it."""
    if kind == "choice":
        return spec.choices[name].encode(name, v)
    if kind == "real":
        return real(v, name)
    return integer(v, name, *_INT_RANGES[kind], what=f"C {kind}")


def _new(ffi: Any, lib: Any, spec: SettingsSpec, values: Mapping[str, Any]) -> Any:
    fields = _fields(spec)
    s = ffi.new(f"{spec.ctype} *")
    getattr(lib, spec.default_fn)(s)
    for k, v in values.items():
        _set(s, fields[k][0], v)
    return s


def fill(ffi: Any, lib: Any, spec: SettingsSpec, settings: Mapping[str, Any]) -> Any:
    """A new ``spec.ctype`` struct: the library's defaults with ``settings`` applied,
    each checked by name (see the module's doc), then the whole by ``spec.check_fn``."""
    fields = _fields(spec)
    values: dict[str, Any] = {}
    for k, v in settings.items():
        if k not in fields:
            raise InvalidArgument(f"unknown {spec.label} setting {k!r} (known: {', '.join(fields)})")
        values[k] = _value(spec, k, fields[k][1], v)
    s = _new(ffi, lib, spec, values)
    if getattr(lib, spec.check_fn)(s) != 0:
        raise InvalidArgument(f"settings: {_outside(ffi, lib, spec, s, settings, values)} ({spec.domain})")
    return s


def _outside(ffi: Any, lib: Any, spec: SettingsSpec, s: Any, settings: Mapping[str, Any],
             values: Mapping[str, Any]) -> str:
    """What of the filled struct ``s`` is outside the domain, as the message says it."""
    if spec.field_fn is not None:
        out = ffi.new("const char **")
        getattr(lib, spec.field_fn)(s, out)
        name = ffi.string(out[0]).decode().replace(".", "_")  # a nested field as exposed
        return f"{name}={settings[name] if name in settings else read(spec, s)[name]!r} outside its domain"
    # name the settings that are outside the domain on their own (the others at their defaults)
    check = getattr(lib, spec.check_fn)
    bad = [k for k in values if check(_new(ffi, lib, spec, {k: values[k]})) != 0]
    given = ", ".join(f"{k}={settings[k]!r}" for k in (bad or values))
    what = "outside its domain" if len(bad) == 1 else "outside their domains" if bad else \
        "together outside the domain"
    return f"{given} {what}"


def parse_assignment(spec: SettingsSpec, text: str, option: str) -> tuple[str, Any]:
    """``NAME=VALUE`` as a command line gives a setting of ``spec``: the name checked
    against the struct's, the value as its kind takes it (a choice by name, a real a
    finite number, an integer an integer). The domain is checked when the struct is
    filled (:func:`fill`). Raises :class:`~attitude_c._options.OptionError` (a
    ValueError) naming ``option``."""
    name, sep, value = text.partition("=")
    name, value = name.strip(), value.strip()
    if not sep or not name or not value:
        raise OptionError(f"{option} expects NAME=VALUE, got {text!r}")
    known = kinds(spec)
    if name not in known:
        raise OptionError(f"{option}: unknown {spec.label} setting {name!r} (known: {', '.join(known)})")
    if known[name] == "choice":
        return name, value
    try:
        v: float | int = float(value) if known[name] == "real" else int(value, 0)
    except ValueError:
        what = "a number" if known[name] == "real" else "an integer"
        raise OptionError(f"{option} {name}: expected {what}, got {value!r}") from None
    if not np.isfinite(v):
        raise OptionError(f"{option} {name}: must be finite, got {value!r}")
    return name, v
