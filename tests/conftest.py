"""Shared pytest fixtures and helpers.

Run the suite from the checkout's root with ``python -m pytest`` (``invoke
test`` does): the root is then on sys.path, so the tests import the tooling
layer (``toolchain``) as a package; ``attitude_c`` is the installed (``pip
install -e .``) package. Nothing here edits sys.path.

Toolchain rule: a test that needs a toolchain calls ``require_target(name)``
(or ``require_tools``). Locally a missing tool skips the test with a
message saying what to install; in CI (``CI`` set in the environment) it
fails, because CI installs every toolchain (see scripts/setup.sh).
"""

from __future__ import annotations

import _posixsubprocess
import os
import shutil
import subprocess
from pathlib import Path

import pytest

from toolchain import (
    targets as _targets,  # the checkout's root is on sys.path: python -m pytest from it
)

ROOT = Path(__file__).resolve().parents[1]

IN_CI = bool(os.environ.get("CI"))


def _missing(msg: str) -> None:
    if IN_CI:
        pytest.fail(f"{msg} (CI must install it: see scripts/setup.sh)")
    pytest.skip(msg)


def require_tools(*tools: str, apt: str) -> None:
    """Skip (locally) or fail (CI) unless every tool is on PATH."""
    missing = [t for t in tools if shutil.which(t) is None]
    if missing:
        _missing(f"needs {', '.join(missing)}: apt-get install {apt}")


def require_target(name: str) -> _targets.Target:
    """Load toolchain target ``name``; skip/fail with an install hint if absent."""
    t = _targets.load(name)
    missing = t.missing_tools()
    if missing:
        _missing(f"target {name} needs {', '.join(missing)}: {t.install_hint()}")
    return t


# ---- test tiers ----
# A `system` test builds a toolchain target, starts a process or runs the simulator end to
# end; `invoke test --fast` (pytest --fast) runs the others: unit and differential tests on
# the host, what a developer runs on every change. The marks are kept true by a guard: a test
# without the mark that starts a process fails (in its body on every run; in its fixtures too
# under --fast, where session fixtures are not shared with system tests).

SYSTEM_MARKS = ("system", "qemu", "s51", "slow")  # each implies the system tier


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "system: builds a toolchain target, starts a process or runs the "
                            "simulator end to end (not in the fast tier: invoke test --fast)")


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--fast", action="store_true",
                     help="the fast tier: deselect `system` tests (toolchains, processes, simulator runs)")


def is_system(item: pytest.Item) -> bool:
    return any(item.get_closest_marker(m) is not None for m in SYSTEM_MARKS)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if not config.getoption("--fast"):
        return
    keep = [it for it in items if not is_system(it)]
    gone = [it for it in items if is_system(it)]
    if gone:
        config.hook.pytest_deselected(items=gone)
        items[:] = keep


class _ProcessGuard:
    """While active, every way of starting a process raises: the fork/exec primitives
    under subprocess, multiprocessing, pty and os.system."""

    NAMES = ((subprocess, "_fork_exec"), (_posixsubprocess, "fork_exec"), (os, "fork"), (os, "forkpty"),
             (os, "posix_spawn"), (os, "posix_spawnp"), (os, "system"))

    def __init__(self, item: pytest.Item) -> None:
        self.item = item
        self.saved: list[tuple[object, str, object]] = []

    def refuse(self, *args: object, **kwargs: object) -> None:
        raise RuntimeError(f"{self.item.nodeid} starts a process but is not marked system: add "
                           "@pytest.mark.system (tests/conftest.py, test tiers)")

    def __enter__(self) -> None:
        for mod, name in self.NAMES:
            if hasattr(mod, name):
                self.saved.append((mod, name, getattr(mod, name)))
                setattr(mod, name, self.refuse)

    def __exit__(self, *exc: object) -> None:
        for mod, name, orig in self.saved:
            setattr(mod, name, orig)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_setup(item: pytest.Item):
    if item.config.getoption("--fast") and not is_system(item):
        with _ProcessGuard(item):
            return (yield)
    return (yield)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item: pytest.Item):
    if is_system(item):
        return (yield)
    with _ProcessGuard(item):
        return (yield)


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


@pytest.fixture(scope="session")
def build_root(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A per-session scratch build directory (never inside the source tree)."""
    return tmp_path_factory.mktemp("build")


def clean_copy(dst: Path, *paths: str) -> Path:
    """Copy the files git knows under ``paths`` (tracked, or new and not
    ignored: what a fresh clone has, plus uncommitted work) to ``dst``, so a
    build there reuses no stale output of the working tree."""
    files = subprocess.run(["git", "ls-files", "-co", "--exclude-standard", *paths], cwd=ROOT, check=True,
                           capture_output=True, text=True).stdout.split()
    for f in files:
        if (ROOT / f).is_file():  # a deleted but still tracked file is skipped
            (dst / f).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / f, dst / f)
    return dst


# ---- truth for the attitude filters' tests (test_ahrs.py, test_ahrs_thesis.py) ----

G = 9.81  # m/s², the filters' default gravity
M_N = (0.0, 20.0, -40.0)  # µT, ENU: north and down (dip 63°)


def motion(n: int, rate: float, w: tuple[float, float, float], q0=None, bias=(0, 0, 0), noise=0.0, seed=1):
    """Constant body rate w: truth q_k = q0 ⊗ exp(w t_k) exactly (closed form); ideal
    sensors (gyro w + bias; specific force and field rotated into the body), plus white
    noise of σ ``noise`` rad/s (20× that in m/s², 50× in µT) when ``noise`` > 0.
    Returns gyr, acc, mag (n, 3) and the truth (n, 4)."""
    import numpy as np

    from attitude_c import reference as ref

    rng = np.random.default_rng(seed)
    t = np.arange(n) / rate
    wv = np.asarray(w, float)
    q0 = np.array([1.0, 0, 0, 0]) if q0 is None else np.asarray(q0, float)
    truth = ref.quat_multiply(q0, ref.rotvec_to_quat(np.outer(t, wv)))
    C = ref.quat_to_dcm(truth)
    acc = np.einsum("nji,j->ni", C, [0.0, 0.0, G])  # C^T up·g
    mag = np.einsum("nji,j->ni", C, np.asarray(M_N))
    gyr = np.tile(wv, (n, 1)) + np.asarray(bias, float)
    if noise:
        gyr = gyr + noise * rng.standard_normal(gyr.shape)
        acc = acc + 20 * noise * rng.standard_normal(acc.shape)
        mag = mag + 50 * noise * rng.standard_normal(mag.shape)
    return gyr, acc, mag, truth


def angle_deg(qa, qb):
    """Rotation angle between attitudes, degrees."""
    import numpy as np

    from attitude_c import reference as ref

    return np.degrees(ref.quat_angle(qa, qb))


def broad_mat(path: Path, n: int = 50, **fields) -> Path:
    """A BROAD-format .mat trial of ``n`` samples at 100 Hz, at rest and level (gyro 0.01 rad/s
    on each axis), ``fields`` replacing any of its arrays (a test's fault). Needs SciPy."""
    import numpy as np
    from scipy.io import savemat

    d = {"imu_gyr": np.full((n, 3), 0.01), "imu_acc": np.tile([0, 0, 9.81], (n, 1)),
         "imu_mag": np.tile([20.0, 0, -40.0], (n, 1)), "opt_quat": np.tile([1.0, 0, 0, 0], (n, 1)),
         "movement": np.ones((n, 1)), "sampling_rate": np.array([[100.0]])}
    d.update(fields)
    savemat(path, d)
    return path


def peak_memory(fn):
    """``(fn(), the peak of Python's allocations while it ran, bytes)`` (tracemalloc)."""
    import tracemalloc

    tracemalloc.start()
    try:
        out = fn()
        return out, tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
