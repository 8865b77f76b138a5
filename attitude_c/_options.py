"""The one validator of option values: the ``attitude`` commands' numeric
options (:mod:`attitude_c.cli.options`) and the simulator's option table
(:mod:`attitude_c.sim.options`) parse with these.

Each converter takes the option's text as on a command line
(``conv("30,20,25")``) or, through ``conv.value(x)``, the value as a Python
or TOML document holds it (a number, a list of numbers). A value that is not
a number, not finite (``nan``, ``inf``), of the wrong sign or outside its
range raises :class:`OptionError` (a ValueError) naming the option, the rule
and the value given; a value of the wrong type :class:`OptionTypeError` (a
TypeError). Both are also ``argparse.ArgumentTypeError``, so that a parser
using a converter as ``type=`` prints the message as it is.
"""

from __future__ import annotations

import argparse
import math
from typing import Any


class OptionError(argparse.ArgumentTypeError, ValueError):
    """A bad option value: the message names the option."""


class OptionTypeError(argparse.ArgumentTypeError, TypeError):
    """An option value of the wrong type: the message names the option."""


def _is_number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _rule(gt: float | None, ge: float | None, lt: float | None, le: float | None) -> str:
    parts = []
    for sign, bound in ((">", gt), (">=", ge), ("<", lt), ("<=", le)):
        if bound is not None:
            parts.append(f"{sign} {bound:g}")
    return " and ".join(parts)


class Real:
    """A finite float with the given bounds (``gt``: > , ``ge``: >=, ``lt``: <, ``le``: <=)."""

    def __init__(self, option: str, *, gt: float | None = None, ge: float | None = None,
                 lt: float | None = None, le: float | None = None) -> None:
        self.option, self.bounds = option, (gt, ge, lt, le)
        rule = _rule(gt, ge, lt, le)
        self.want = "a finite number" + (f" {rule}" if rule else "")
        # argparse names the type in some messages; tests/test_cli_faults.py reads whether it has a lower bound
        self.__name__ = "number" if gt is not None or ge is not None else "signed number"

    def __call__(self, text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            raise OptionError(f"{self.option}: expected a number, got {text!r}") from None
        return self._check(v, repr(text))

    def value(self, x: Any) -> float:
        if isinstance(x, str):
            return self(x)
        if not _is_number(x):
            raise OptionTypeError(f"{self.option}: expected a number, got {x!r}")
        try:
            v = float(x)
        except OverflowError:
            raise OptionError(f"{self.option}: must be {self.want}, got {x!r}") from None
        return self._check(v, repr(x))

    def _check(self, v: float, shown: str) -> float:
        gt, ge, lt, le = self.bounds
        if (not math.isfinite(v) or gt is not None and not v > gt or ge is not None and not v >= ge
                or lt is not None and not v < lt or le is not None and not v <= le):
            raise OptionError(f"{self.option}: must be {self.want}, got {shown}")
        return v


class Integer:
    """An integer (decimal, or 0x / 0o / 0b) in ``lo..hi`` (either bound may be open)."""

    __name__ = "integer"

    def __init__(self, option: str, lo: int | None = None, hi: int | None = None) -> None:
        self.option, self.lo, self.hi = option, lo, hi
        self.want = (f"in {lo}..{hi}" if lo is not None and hi is not None else f">= {lo}" if lo is not None
                     else f"<= {hi}" if hi is not None else "")

    def __call__(self, text: str) -> int:
        try:
            v = int(text, 0)
        except ValueError:
            raise OptionError(f"{self.option}: expected an integer, got {text!r}") from None
        return self._check(v)

    def value(self, x: Any) -> int:
        if isinstance(x, str):
            return self(x)
        if isinstance(x, bool) or not isinstance(x, int):
            raise OptionTypeError(f"{self.option}: expected an integer, got {x!r}")
        return self._check(x)

    def _check(self, v: int) -> int:
        if self.lo is not None and v < self.lo or self.hi is not None and v > self.hi:
            raise OptionError(f"{self.option}: must be {self.want}, got {v}")
        return v


class Floats:
    """``counts`` finite numbers, comma-separated (``triple``: one number stands for three)."""

    def __init__(self, option: str, counts: tuple[int, ...], *, spread: bool = False) -> None:
        self.option, self.counts, self.spread = option, counts, spread
        self.__name__ = "triple" if spread else "numbers"

    def _how_many(self) -> str:
        if self.spread:
            return "one value or three comma-separated values"
        return f"{' or '.join(map(str, self.counts))} comma-separated values"

    def __call__(self, text: str) -> tuple[float, ...]:
        parts = [p for p in text.replace(" ", "").split(",") if p != ""]
        if self.spread and len(parts) == 1:
            parts = parts * 3
        if len(parts) not in self.counts:
            raise OptionError(f"{self.option}: give {self._how_many()}, got {text!r}")
        try:
            vals = tuple(float(p) for p in parts)
        except ValueError:
            raise OptionError(f"{self.option}: not a number in {text!r}") from None
        return self._check(vals, repr(text))

    def value(self, x: Any) -> tuple[float, ...]:
        if isinstance(x, str):
            return self(x)
        if self.spread and _is_number(x):
            x = [x] * 3
        if not isinstance(x, (list, tuple)) or not all(_is_number(v) for v in x):
            raise OptionTypeError(f"{self.option}: give {self._how_many()} (a list of numbers), got {x!r}")
        if len(x) not in self.counts:
            raise OptionError(f"{self.option}: give {self._how_many()}, got {x!r}")
        try:
            vals = tuple(float(v) for v in x)
        except OverflowError:
            vals = (math.inf,)
        return self._check(vals, repr(x))

    def _check(self, vals: tuple[float, ...], shown: str) -> tuple[float, ...]:
        if not all(math.isfinite(v) for v in vals):
            raise OptionError(f"{self.option}: values must be finite, got {shown}")
        return vals


def real(option: str, *, gt: float | None = None, ge: float | None = None, lt: float | None = None,
         le: float | None = None) -> Real:
    """A finite float with the given bounds (``gt``: > , ``ge``: >=, ``lt``: <, ``le``: <=)."""
    return Real(option, gt=gt, ge=ge, lt=lt, le=le)


def integer(option: str, lo: int | None = None, hi: int | None = None) -> Integer:
    """An integer (decimal, or 0x / 0o / 0b) in ``lo..hi`` (either bound may be open)."""
    return Integer(option, lo, hi)


def triple(option: str) -> Floats:
    """One finite number or three comma-separated ones (``X,Y,Z``)."""
    return Floats(option, (3,), spread=True)


def floats(option: str, counts: tuple[int, ...]) -> Floats:
    """Exactly one of ``counts`` comma-separated finite numbers."""
    return Floats(option, counts)


def positive(option: str) -> Real:
    """A finite number > 0 (durations, periods, rates)."""
    return real(option, gt=0)


def nonneg(option: str) -> Real:
    """A finite number >= 0."""
    return real(option, ge=0)


def probability(option: str, below: float = 1.0) -> Real:
    """A probability in [0, ``below``) (bit error rate: below 0.5)."""
    return real(option, ge=0, lt=below)
