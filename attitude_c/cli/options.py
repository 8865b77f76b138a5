"""The one validator of the ``attitude`` commands' numeric options.

Every numeric option of every subcommand is parsed by :func:`real`,
:func:`integer` or :func:`triple` (``type=`` of ``add_argument``): a value
that is not a number, not finite (``nan``, ``inf``), of the wrong sign or
outside its range is a usage error (one line, exit status 2, docs/cli.md)
naming the option, the rule and the value given, before the command
starts. Nothing else in :mod:`attitude_c.cli` converts an option to a
number (tests/test_cli_faults.py checks every numeric option of every
command with ``nan``, ``-5`` and ``x``).
"""

from __future__ import annotations

import argparse
import math
from typing import Any, Callable


def _rule(gt: float | None, ge: float | None, lt: float | None, le: float | None) -> str:
    parts = []
    if gt is not None:
        parts.append(f"> {gt:g}")
    if ge is not None:
        parts.append(f">= {ge:g}")
    if lt is not None:
        parts.append(f"< {lt:g}")
    if le is not None:
        parts.append(f"<= {le:g}")
    return " and ".join(parts)


def real(option: str, *, gt: float | None = None, ge: float | None = None, lt: float | None = None,
         le: float | None = None) -> Callable[[str], float]:
    """A finite float with the given bounds (``gt``: > , ``ge``: >=, ``lt``: <, ``le``: <=)."""
    rule = _rule(gt, ge, lt, le)
    want = "a finite number" + (f" {rule}" if rule else "")

    def conv(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{option}: expected a number, got {text!r}") from None
        if (not math.isfinite(v) or gt is not None and not v > gt or ge is not None and not v >= ge
                or lt is not None and not v < lt or le is not None and not v <= le):
            raise argparse.ArgumentTypeError(f"{option}: must be {want}, got {text!r}")
        return v

    # argparse names the type in some messages; tests/test_cli_faults.py reads whether it has a lower bound
    conv.__name__ = "number" if gt is not None or ge is not None else "signed number"
    return conv


def integer(option: str, lo: int | None = None, hi: int | None = None) -> Callable[[str], int]:
    """An integer (decimal, or 0x / 0o / 0b) in ``lo..hi`` (either bound may be open)."""
    if lo is not None and hi is not None:
        want = f"in {lo}..{hi}"
    elif lo is not None:
        want = f">= {lo}"
    elif hi is not None:
        want = f"<= {hi}"
    else:
        want = ""

    def conv(text: str) -> int:
        try:
            v = int(text, 0)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{option}: expected an integer, got {text!r}") from None
        if lo is not None and v < lo or hi is not None and v > hi:
            raise argparse.ArgumentTypeError(f"{option}: must be {want}, got {v}")
        return v

    conv.__name__ = "integer"
    return conv


def triple(option: str) -> Callable[[str], tuple[float, float, float]]:
    """One finite number or three comma-separated ones (``X,Y,Z``)."""
    def conv(text: str) -> tuple[float, float, float]:
        parts = [p for p in text.replace(" ", "").split(",") if p != ""]
        if len(parts) == 1:
            parts = parts * 3
        if len(parts) != 3:
            raise argparse.ArgumentTypeError(f"{option}: give one value or three comma-separated "
                                             f"values, got {text!r}")
        try:
            x, y, z = (float(p) for p in parts)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{option}: not a number in {text!r}") from None
        if not all(math.isfinite(v) for v in (x, y, z)):
            raise argparse.ArgumentTypeError(f"{option}: values must be finite, got {text!r}")
        return x, y, z

    conv.__name__ = "triple"
    return conv


def pair(option: str, first: Callable[[str], Any], second: Callable[[str], Any],
         form: str = "A:B") -> Callable[[str], tuple[Any, Any]]:
    """``A:B``, each part through its own converter (``real``, ``integer``, a choice)."""
    def conv(text: str) -> tuple[Any, Any]:
        if ":" not in text:
            raise argparse.ArgumentTypeError(f"{option} must look like {form}, got {text!r}")
        a, b = text.split(":", 1)
        return first(a), second(b)

    conv.__name__ = "pair"
    return conv


def choice(option: str, allowed: tuple[str, ...]) -> Callable[[str], str]:
    """One of ``allowed`` (for a part of a :func:`pair`)."""
    def conv(text: str) -> str:
        if text not in allowed:
            raise argparse.ArgumentTypeError(f"{option}: choose from {', '.join(allowed)}, got {text!r}")
        return text

    return conv


def positive(option: str) -> Callable[[str], float]:
    """A finite number > 0 (durations, periods, rates)."""
    return real(option, gt=0)


def nonneg(option: str) -> Callable[[str], float]:
    """A finite number >= 0."""
    return real(option, ge=0)


def probability(option: str, below: float = 1.0) -> Callable[[str], float]:
    """A probability in [0, ``below``) (bit error rate: below 0.5)."""
    return real(option, ge=0, lt=below)
