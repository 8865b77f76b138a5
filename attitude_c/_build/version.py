"""The libattitude version, read from its one source,
``csrc/include/attitude/version.h`` (enums ``ATT_VERSION_MAJOR``, ``_MINOR``,
``_PATCH`` and ``_SO``, the soname's N).

Build-time helper with no imports beyond the standard library: ``setup.py``
loads this file by path (the Python distribution's version) and
``invoke cross-build`` imports it. At run time ``attitude_c.__version__``
comes from the compiled library's enums instead (the header is not
installed with the wheel). CMake and the Makefile parse the same lines.
"""

from __future__ import annotations

import re
from pathlib import Path

HEADER = Path(__file__).resolve().parents[2] / "csrc" / "include" / "attitude" / "version.h"
PARTS = ("MAJOR", "MINOR", "PATCH", "SO")


def read(header: Path = HEADER) -> dict[str, int]:
    """``{"MAJOR": 0, "MINOR": 1, "PATCH": 0, "SO": 0}`` from the header."""
    text = header.read_text()
    out = {}
    for part in PARTS:
        m = re.search(rf"^\s*ATT_VERSION_{part} = (\d+)", text, re.MULTILINE)
        if m is None:
            raise ValueError(f"{header}: no line 'ATT_VERSION_{part} = <number>'")
        out[part] = int(m.group(1))
    return out


def version(header: Path = HEADER) -> str:
    """``MAJOR.MINOR.PATCH``."""
    v = read(header)
    return f"{v['MAJOR']}.{v['MINOR']}.{v['PATCH']}"
