"""Text files read by the package's readers, bounded whatever the file holds.

The readers of recordings (``attitude ahrs``'s CSV, ``attitude view --replay``
and ``--stdin``) take their lines through this module, so that a file that is
not text -- a sparse file of NUL bytes, an image, a gigabyte without a newline --
is refused early and in one short line instead of being read whole:

* :func:`probe_text`: the first :data:`PROBE_BYTES` bytes of a file hold no NUL
  byte (text never does; binary files almost always do near their start);
* :func:`lines`: the lines of a binary stream, UTF-8 (a byte-order mark on the
  first line dropped), each at most :data:`MAX_LINE` bytes: a longer line is
  reported (and skipped without being held in memory), as is a line that is not
  UTF-8 or holds a NUL byte;
* :func:`clip`: a piece of a file (or anything a user gave) cut to a length an
  error line can carry, with its full length said.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import IO

from .errors import InvalidArgument

__all__ = ["MAX_LINE", "PROBE_BYTES", "clip", "lines", "probe_text"]

#: The longest line a reader accepts (bytes). attitude-rx's longest JSON Lines record is
#: under 1 KiB; a CSV row of a recording a few hundred bytes. 1 MiB leaves room for anything
#: a producer may add while bounding what one line can cost.
MAX_LINE = 1 << 20
#: Bytes read from a file's start to tell text from binary content.
PROBE_BYTES = 1024
#: Characters of a file's content quoted in an error line.
CLIP = 80

_BOM = "\ufeff"


def clip(text: str, limit: int = CLIP) -> str:
    """``text`` cut to ``limit`` characters, its length said when cut (``clip(repr(x))`` to quote)."""
    if len(text) <= limit:
        return text
    return f"{text[:limit]}... ({len(text):,} characters)"


def probe_text(path: str | Path) -> None:
    """Raise :class:`InvalidArgument` naming ``path`` when its first bytes hold a NUL byte."""
    with open(path, "rb") as fh:
        head = fh.read(PROBE_BYTES)
    at = head.find(b"\0")
    if at >= 0:
        raise InvalidArgument(f"{path}: not a text file (a NUL byte at offset {at})")


def lines(stream: IO[bytes], max_line: int = MAX_LINE) -> Iterator[tuple[int, str, str | None]]:
    """``(line number, text, problem)`` for each line of ``stream`` (1-based;
    ``problem`` None, or why the line cannot be read, its ``text`` then empty).
    Never holds more than ``max_line`` bytes of one line."""
    lineno = 0
    while True:
        raw = stream.readline(max_line + 1)
        if not raw:
            return
        lineno += 1
        if len(raw) > max_line and not raw.endswith(b"\n"):
            while raw and not raw.endswith(b"\n"):  # skip the rest of the line, a bounded piece at a time
                raw = stream.readline(max_line)
            yield lineno, "", f"longer than {max_line:,} bytes"
            continue
        yield (lineno, *decode(raw, lineno == 1))


def decode(raw: bytes, first: bool = False) -> tuple[str, str | None]:
    """One line's bytes as text: ``(text, None)``, or ``("", problem)``."""
    if b"\0" in raw:
        return "", "a NUL byte (binary content)"
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        return "", f"not UTF-8 text (byte {exc.start})"
    return (text[1:] if first and text.startswith(_BOM) else text), None
