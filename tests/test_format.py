"""Every C source and header of the project is formatted with the repository's .clang-format."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest
from conftest import ROOT

# The C trees the style covers (the same list `invoke format` applies it to): the
# library, its host/app/test programs, the firmware, the C benches, the s51 harness
# and the consumer project.
from toolchain.tasks.core import C_FORMAT_GLOBS as C_GLOBS

pytestmark = pytest.mark.system  # runs clang-format


def c_files() -> list[Path]:
    out: set[Path] = set()
    for g in C_GLOBS:
        out.update(ROOT.glob(g))
    return sorted(out)


def test_c_sources_are_clang_formatted():
    exe = shutil.which("clang-format")
    if exe is None:
        pytest.skip("clang-format not installed (apt-get install clang-format, or scripts/setup.sh)")
    files = c_files()
    assert len(files) > 40  # the globs still find the tree
    r = subprocess.run([exe, "--dry-run", "--Werror", *map(str, files)], cwd=ROOT, check=False,
                       capture_output=True, text=True)
    bad = sorted({line.split(":", 1)[0] for line in r.stderr.splitlines() if ": error:" in line})
    assert r.returncode == 0, ("not clang-formatted (run `invoke format`): "
                               + ", ".join(str(Path(b).relative_to(ROOT)) for b in bad))
