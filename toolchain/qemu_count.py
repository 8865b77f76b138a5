"""Exact instruction counts of a program on an emulated core (qemu-user).

``qemu-arm -cpu ti925t -singlestep -d nochain,exec`` makes every
translation block one guest instruction, never chains blocks, and logs a
``Trace`` line each time a block is executed, so the number of ``Trace``
lines is the number of guest instructions executed (user-mode code only;
system calls run on the host and count as one ``svc`` instruction).

The count includes start-up (C runtime, semihosting or libc init), so to
get the cost of one operation run the same program with two iteration
counts and take the difference::

    from toolchain.qemu_count import count_instructions, per_iteration
    n = count_instructions("build/armv4t-bare/bench_rv3", ["rv3", "1000"])
    per = per_iteration("build/armv4t-bare/bench_rv3", lambda k: ["rv3", str(k)], 100, 1100)

Newer qemu (8.1+) renamed ``-singlestep`` to ``-one-insn-per-tb``; the
right spelling is picked automatically.
"""

from __future__ import annotations

import functools
import os
import shutil
import subprocess
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Callable

__all__ = ["QemuCountError", "count_instructions", "per_iteration"]

_MARK = b"Trace "


class QemuCountError(RuntimeError):
    """The emulator is missing, the program failed, or it timed out."""


@functools.cache
def _single_step_flag(qemu: str) -> str:
    try:
        out = subprocess.run([qemu, "-h"], capture_output=True, timeout=30,
                             check=False).stdout
    except (OSError, subprocess.TimeoutExpired):  # pragma: no cover - reported by the caller
        return "-singlestep"
    return "-one-insn-per-tb" if b"-one-insn-per-tb" in out else "-singlestep"


def count_instructions(exe: str | os.PathLike[str], args: Sequence[str] = (), *,
                       cpu: str | None = "ti925t", qemu: str = "qemu-arm",
                       stdin: bytes | None = None, timeout: float = 600,
                       check: bool = True) -> int:
    """Number of guest instructions ``exe args...`` executes under ``qemu``.

    ``cpu`` selects the emulated core (default ``ti925t``, an ARMv4T core
    like the ARM920T; ``None`` = qemu's default). The program's stdout is
    discarded; its exit status must be 0 unless ``check`` is False.
    """
    if shutil.which(qemu) is None:
        raise QemuCountError(f"{qemu} not found; apt-get install qemu-user")
    exe = Path(exe)
    if not exe.exists():
        raise QemuCountError(f"program {exe} does not exist")
    cmd = [qemu]
    if cpu:
        cmd += ["-cpu", cpu]
    cmd += [_single_step_flag(qemu), "-d", "nochain,exec", str(exe), *map(str, args)]
    # The exec log goes to stderr; stream it and count lines starting with
    # "Trace " without keeping it (it is ~80 bytes per instruction).
    proc = subprocess.Popen(cmd, stdin=subprocess.PIPE if stdin is not None else subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    assert proc.stderr is not None
    if stdin is not None:
        assert proc.stdin is not None
        proc.stdin.write(stdin)
        proc.stdin.close()
    count = 0
    tail = b"\n"  # previous chunk's last bytes, so a mark split across chunks counts once
    other: list[bytes] = []
    deadline = time.monotonic() + timeout
    try:
        while True:
            chunk = proc.stderr.read(1 << 20)
            if not chunk:
                break
            buf = tail + chunk
            count += buf.count(b"\n" + _MARK)
            # keep enough to detect "\nTrace " straddling the boundary
            tail = buf[-len(_MARK):]
            if len(other) < 50 and b"qemu:" in chunk:
                other.append(chunk[chunk.find(b"qemu:"):][:300])
            if time.monotonic() > deadline:
                proc.kill()
                raise QemuCountError(f"{' '.join(cmd)} timed out after {timeout} s")
        rc = proc.wait(timeout=max(1.0, deadline - time.monotonic()))
    except subprocess.TimeoutExpired as exc:
        proc.kill()
        raise QemuCountError(f"{' '.join(cmd)} timed out after {timeout} s") from exc
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    if check and rc != 0:
        msg = b"".join(other).decode(errors="replace")
        raise QemuCountError(f"{' '.join(cmd)} exited with status {rc}: {msg}")
    return count


def per_iteration(exe: str | os.PathLike[str], make_args: Callable[[int], Sequence[str]],
                  n_small: int, n_large: int, **kwargs: object) -> float:
    """Instructions per iteration: (count(n_large) - count(n_small)) / (n_large - n_small).

    ``make_args(k)`` returns the program arguments for ``k`` iterations;
    start-up and shut-down costs cancel out in the difference.
    """
    if n_large <= n_small:
        raise ValueError(f"n_large ({n_large}) must be greater than n_small ({n_small})")
    a = count_instructions(exe, make_args(n_small), **kwargs)  # type: ignore[arg-type]
    b = count_instructions(exe, make_args(n_large), **kwargs)  # type: ignore[arg-type]
    return (b - a) / (n_large - n_small)


if __name__ == "__main__":  # pragma: no cover
    import sys

    if len(sys.argv) < 2:
        sys.exit("usage: python -m toolchain.qemu_count EXE [ARGS...]")
    print(count_instructions(sys.argv[1], sys.argv[2:]))
