"""``python -m toolchain.simulate ARGS``: ``attitude simulate ARGS`` with the tooling
layer's acquisition sources registered (``--firmware s51``: the AT89S51 firmware
in s51, toolchain/firmware.py). Run it from the source checkout's root."""

from __future__ import annotations

import sys
from collections.abc import Sequence

from attitude_c.cli import main as attitude_main

from . import firmware  # noqa: F401 - registers the "s51" source


def main(argv: Sequence[str] | None = None) -> int:
    return attitude_main(["simulate", *(sys.argv[1:] if argv is None else argv)])


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
