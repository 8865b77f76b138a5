"""Link tasks: `invoke fuzz --seconds N` runs the libFuzzer target of the
link machines (csrc/fuzz/fuzz_link_receiver.c) under ASan + UBSan."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

from invoke import task

ROOT = Path(__file__).resolve().parents[2]
FUZZ_SRC = ROOT / "csrc" / "fuzz" / "fuzz_link_receiver.c"
LIB = [ROOT / "csrc" / "src" / n for n in ("link_sender.c", "link_sender_aux.c", "link_receiver.c")]
APT_HINT = "apt-get install clang libclang-rt-14-dev"


def build_fuzzer(out_dir: Path, cc: str = "clang") -> Path:
    """Build the fuzz target with libFuzzer, ASan and UBSan; returns the executable."""
    if shutil.which(cc) is None:
        raise RuntimeError(f"{cc} not found: {APT_HINT}")
    out_dir.mkdir(parents=True, exist_ok=True)
    exe = out_dir / "fuzz_link_receiver"
    cmd = [cc, "-std=c99", "-g", "-O1", "-Wall", "-Wextra", "-Wpedantic", "-Werror",
           "-fsanitize=fuzzer,address,undefined", "-fno-sanitize-recover=all",
           f"-I{ROOT / 'csrc' / 'include'}", str(FUZZ_SRC), *map(str, LIB), "-o", str(exe)]
    subprocess.run(cmd, check=True)
    return exe


def run_fuzzer(exe: Path, seconds: int, corpus: Path, artifacts: Path) -> subprocess.CompletedProcess:
    """Run libFuzzer for `seconds`; a crash leaves its input in `artifacts`."""
    corpus.mkdir(parents=True, exist_ok=True)
    artifacts.mkdir(parents=True, exist_ok=True)
    cmd = [str(exe), f"-max_total_time={seconds}", "-max_len=1024", "-timeout=10",
           "-rss_limit_mb=1024", f"-artifact_prefix={artifacts}/", "-print_final_stats=1", str(corpus)]
    return subprocess.run(cmd, check=False, capture_output=True, text=True, timeout=seconds + 120)


@task(help={"seconds": "how long to fuzz (default 60)", "corpus": "corpus directory (default fuzz-corpus/link)"})
def fuzz(c, seconds=60, corpus=""):
    """Fuzz the link receiver and sender (libFuzzer + ASan + UBSan)."""
    build = ROOT / "build" / "fuzz"
    exe = build_fuzzer(build)
    corp = Path(corpus) if corpus else ROOT / "fuzz-corpus" / "link"
    proc = run_fuzzer(exe, int(seconds), corp, build / "artifacts")
    tail = "\n".join(proc.stderr.strip().splitlines()[-12:])
    print(tail)
    if proc.returncode != 0:
        raise SystemExit(f"fuzz: the fuzzer found a problem (exit {proc.returncode}); "
                         f"reproducer in {build / 'artifacts'}")
    print(f"fuzz: {seconds} s clean")


