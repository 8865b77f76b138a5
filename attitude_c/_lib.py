"""Access to the compiled CFFI modules.

``lib(precision)`` returns ``(ffi, lib)`` for ``"f64"`` or ``"f32"``: the
same C sources compiled with ``att_real`` = double or float.
"""

from __future__ import annotations

import importlib
from types import ModuleType
from typing import Any

_PRECISIONS = ("f64", "f32")
_cache: dict[str, ModuleType] = {}


def _module(precision: str) -> ModuleType:
    if precision not in _PRECISIONS:
        from .errors import InvalidArgument

        raise InvalidArgument(
            f"precision must be one of {_PRECISIONS!r} here, got {precision!r}"
        )
    cached = _cache.get(precision)
    if cached is not None:
        return cached
    try:
        mod = importlib.import_module(f"{__package__}._att_{precision}")
    except ImportError as exc:  # pragma: no cover - depends on install
        raise ImportError(
            "attitude_c's C extension is not built: run `pip install -e .` "
            "(or `invoke build`) from the project root"
        ) from exc
    _cache[precision] = mod
    return mod


def ffi_lib(precision: str = "f64") -> tuple[Any, Any]:
    """Return ``(ffi, lib)`` of the extension built for ``precision``."""
    mod = _module(precision)
    return mod.ffi, mod.lib
