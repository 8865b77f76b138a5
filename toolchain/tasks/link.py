"""Link tasks: `invoke fuzz` runs the libFuzzer targets of the link machines
(legacy and v2), the block format and the GNSS parser (csrc/fuzz/fuzz_link.c, fuzz_link2.c, fuzz_block.c,
fuzz_gnss.c) under ASan +
UBSan; `--coverage` then measures the line coverage their corpora give each
source (clang source-based coverage)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

from invoke import task

ROOT = Path(__file__).resolve().parents[2]
FUZZ_DIR = ROOT / "csrc" / "fuzz"
#: target name -> its source; both link every source below
TARGETS = {"link": FUZZ_DIR / "fuzz_link.c", "block": FUZZ_DIR / "fuzz_block.c", "link2": FUZZ_DIR / "fuzz_link2.c",
           "gnss": FUZZ_DIR / "fuzz_gnss.c"}
SRC = ROOT / "csrc" / "src"
LIB = [SRC / n for n in ("link_sender.c", "link_sender_aux.c", "link_receiver.c", "block.c", "block_decode.c",
                         "block_sums.c", "block_channels.c", "common.c", "link2_sender.c", "link2_sender_aux.c",
                         "link2_receiver.c", "gnss_parse.c", "gnss_nmea.c", "gnss_ubx.c")]
#: the sources each target is meant to cover (common.c only has att_status_str: not theirs)
COVERS = {"link": ("link_sender.c", "link_sender_aux.c", "link_receiver.c"),
          "block": ("block.c", "block_decode.c", "block_sums.c", "block_channels.c"),
          "link2": ("link2_sender.c", "link2_sender_aux.c", "link2_receiver.c"),
          "gnss": ("gnss_parse.c", "gnss_nmea.c", "gnss_ubx.c")}
APT_HINT = "apt-get install clang libclang-rt-14-dev llvm"


def _tool(name: str) -> str:
    for cand in (name, f"{name}-14"):
        if shutil.which(cand):
            return cand
    raise RuntimeError(f"{name} not found: {APT_HINT}")


def build_fuzzer(out_dir: Path, target: str = "link", cc: str = "clang", coverage: bool = False) -> Path:
    """Build fuzz target `target` with libFuzzer and ASan + UBSan (or, with
    coverage, with clang's source-based coverage instead); returns the executable."""
    if shutil.which(cc) is None:
        raise RuntimeError(f"{cc} not found: {APT_HINT}")
    out_dir.mkdir(parents=True, exist_ok=True)
    exe = out_dir / (f"fuzz_{target}" + ("_cov" if coverage else ""))
    flags = (["-fsanitize=fuzzer", "-fprofile-instr-generate", "-fcoverage-mapping"] if coverage
             else ["-fsanitize=fuzzer,address,undefined", "-fno-sanitize-recover=all"])
    cmd = [cc, "-std=c99", "-g", "-O1", "-Wall", "-Wextra", "-Wpedantic", "-Werror", *flags,
           f"-I{ROOT / 'csrc' / 'include'}", str(TARGETS[target]), *map(str, LIB), "-o", str(exe)]
    subprocess.run(cmd, check=True)
    return exe


def run_fuzzer(exe: Path, seconds: int, corpus: Path, artifacts: Path) -> subprocess.CompletedProcess:
    """Run libFuzzer for `seconds`; a crash leaves its input in `artifacts`."""
    corpus.mkdir(parents=True, exist_ok=True)
    artifacts.mkdir(parents=True, exist_ok=True)
    cmd = [str(exe), f"-max_total_time={seconds}", "-max_len=1024", "-timeout=10",
           "-rss_limit_mb=1024", f"-artifact_prefix={artifacts}/", "-print_final_stats=1", str(corpus)]
    return subprocess.run(cmd, check=False, capture_output=True, text=True, timeout=seconds + 120)


def line_coverage(target: str, corpus: Path, work: Path) -> dict[str, tuple[int, int]]:
    """Run every input of `corpus` once through the coverage build of `target`;
    {source file name: (lines covered, lines)} for every library source."""
    exe = build_fuzzer(work, target, coverage=True)
    raw = work / f"{target}.profraw"
    prof = work / f"{target}.profdata"
    env = {**os.environ, "LLVM_PROFILE_FILE": str(raw)}
    subprocess.run([str(exe), "-runs=0", str(corpus)], check=True, capture_output=True, env=env, timeout=3600)
    subprocess.run([_tool("llvm-profdata"), "merge", "-sparse", str(raw), "-o", str(prof)], check=True)
    out = subprocess.run([_tool("llvm-cov"), "export", "-summary-only", f"-instr-profile={prof}", str(exe),
                          *map(str, LIB)], check=True, capture_output=True, text=True).stdout
    res = {}
    for f in json.loads(out)["data"][0]["files"]:
        lines = f["summary"]["lines"]
        res[Path(f["filename"]).name] = (lines["covered"], lines["count"])
    return res


@task(help={"seconds": "how long to fuzz each target (default 60)",
            "target": "link, block, link2, gnss or all (default all)",
            "corpus": "corpus directory, one subdirectory per target (default fuzz-corpus)",
            "coverage": "then report the line coverage the corpus gives each source"})
def fuzz(c, seconds=60, target="all", corpus="", coverage=False):
    """Fuzz the link machines, the block format and the GNSS parser (libFuzzer + ASan + UBSan)."""
    build = ROOT / "build" / "fuzz"
    names = list(TARGETS) if target == "all" else [target]
    if any(n not in TARGETS for n in names):
        raise SystemExit(f"fuzz: unknown target {target!r} ({', '.join(TARGETS)}, all)")
    base = Path(corpus) if corpus else ROOT / "fuzz-corpus"
    for name in names:
        exe = build_fuzzer(build, name)
        corp = base / name
        proc = run_fuzzer(exe, int(seconds), corp, build / "artifacts" / name)
        print("\n".join(proc.stderr.strip().splitlines()[-6:]))
        if proc.returncode != 0:
            raise SystemExit(f"fuzz {name}: the fuzzer found a problem (exit {proc.returncode}); "
                             f"reproducer in {build / 'artifacts' / name}")
        print(f"fuzz {name}: {seconds} s clean, corpus {corp} ({len(list(corp.iterdir()))} inputs)")
        if coverage:
            cov = line_coverage(name, corp, build / "coverage")
            for src in COVERS[name]:
                got, total = cov[src]
                print(f"fuzz {name}: {src}: {got}/{total} lines = {100.0 * got / total:.1f} %")


