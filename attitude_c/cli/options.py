"""The one validator of the ``attitude`` commands' numeric options.

Every numeric option of every subcommand is parsed by :func:`real`,
:func:`integer` or :func:`triple` (``type=`` of ``add_argument``; they live in
:mod:`attitude_c._options`, which the simulator's option table shares): a value
that is not a number, not finite (``nan``, ``inf``), of the wrong sign or
outside its range is a usage error (one line, exit status 2, docs/cli.md)
naming the option, the rule and the value given, before the command
starts. Nothing else in :mod:`attitude_c.cli` converts an option to a
number (tests/test_cli_faults.py checks every numeric option of every
command with ``nan``, ``-5`` and ``x``).
"""

from __future__ import annotations

import argparse
from typing import Any, Callable

from .._options import floats, integer, nonneg, positive, probability, real, triple

__all__ = ["choice", "floats", "integer", "nonneg", "pair", "positive", "probability", "real", "triple"]


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
