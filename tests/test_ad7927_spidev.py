"""The AD7927 spidev HAL (csrc/platform/linux) tested against the C twin of the
device model through its operating-system seam (an injected ioctl and sleep:
csrc/platform/linux/tests/test_ad7927_spidev.c), on the host under
ASan + UBSan (gcc and clang) and on ARMv4T Linux (arm-linux-gnueabi, run by
qemu-arm). The platform code is Linux-only, so it is not part of the
bare-metal library and of tests/test_c_programs.py's glob."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import ROOT, require_target

pytestmark = pytest.mark.system  # builds and runs the spidev HAL programs

PLATFORM = ROOT / "csrc" / "platform" / "linux"
TEST_SRC = PLATFORM / "tests" / "test_ad7927_spidev.c"


@pytest.mark.parametrize("target", ["host-asan", "host-clang", "armv4t"])
def test_spidev_hal_against_the_model(target: str, build_root: Path) -> None:
    t = require_target(target)
    exe = t.build_program([TEST_SRC, *sorted((PLATFORM / "src").glob("*.c"))],
                          build_root / target / "spidev" / TEST_SRC.stem,
                          include_dirs=[ROOT / "csrc" / "host", ROOT / "csrc" / "tests", PLATFORM / "include"],
                          lib_sources=sorted((ROOT / "csrc" / "src").glob("*.c"))
                          + sorted((ROOT / "csrc" / "host").glob("*.c")))
    proc = t.run([exe], timeout=300, check=False)
    out = proc.stdout.decode(errors="replace")
    assert proc.returncode == 0, f"{TEST_SRC.name} on {target} failed:\n{out}\n{proc.stderr.decode(errors='replace')}"
    assert out.strip().splitlines()[-1].endswith(" 0 failed"), out


def test_linux_cross_build_carries_the_spidev_hal(tmp_path: Path) -> None:
    """invoke cross-build puts the platform code into Linux targets' libraries
    (and its header next to the others), never into bare-metal ones."""
    from toolchain import targets
    from toolchain.tasks.cross import cross_build_target

    assert [p.name for p in targets.load("armv4t").platform_sources()] == ["ad7927_spidev.c"]
    assert targets.load("armv4t-bare").platform_sources() == []
    assert targets.load("mcs51").platform_sources() == []
    require_target("host")
    products = cross_build_target("host", out=tmp_path / "host")
    assert (products["include"] / "ad7927_spidev.h").exists()
    names = (tmp_path / "host" / "obj").glob("*.o")
    assert "ad7927_spidev.o" in {p.name for p in names}


@pytest.mark.qemu
def test_bench_harness_reads_through_every_hal(build_root: Path) -> None:
    """bench/ad7927_armv4t.c (the instruction counts of bench/ad7927.py): every HAL
    and mode completes its reads (the driver's checks pass against the fake
    device), and the cost per read is exactly linear (the counts are exact)."""
    from toolchain.qemu_count import per_iteration

    src = ROOT / "bench" / "ad7927_armv4t.c"
    lib = sorted((ROOT / "csrc" / "src").glob("*.c"))
    bare = require_target("armv4t-bare")
    lin = require_target("armv4t")
    exe_bare = bare.build_program([src], build_root / "bench" / "ad7927_bare", lib_sources=lib)
    exe_lin = lin.build_program([src, *sorted((PLATFORM / "src").glob("*.c"))], build_root / "bench" / "ad7927_lin",
                                include_dirs=[PLATFORM / "include"], lib_sources=lib)
    for exe, t, hals in ((exe_bare, bare, ("pins", "frames")), (exe_lin, lin, ("pins", "frames", "spidev"))):
        for hal in hals:
            for mode in ("scan", "seq", "fake"):
                assert t.run([exe, hal, mode, "3"], timeout=120, check=False).returncode == 0, (hal, mode)
    a = per_iteration(exe_bare, lambda k: ["frames", "scan", f"{k:03d}"], 2, 5)
    b = per_iteration(exe_bare, lambda k: ["frames", "scan", f"{k:03d}"], 5, 11)
    assert a == b and a == int(a) and 300 < a < 2000  # ~600 instructions per 7-frame scan
