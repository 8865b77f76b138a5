"""Core tasks: build, test, lint, clean, bench."""

from __future__ import annotations

import datetime
import hashlib
import importlib
import itertools
import platform
import shutil
import sys
from pathlib import Path

from invoke import task

ROOT = Path(__file__).resolve().parents[2]
BENCH_DOC = ROOT / "docs" / "benchmarks.md"


def _version_tuple(text: str) -> tuple[int, ...]:
    out = []
    for part in text.split("."):
        digits = "".join(itertools.takewhile(str.isdigit, part))
        if not digits:
            break
        out.append(int(digits))
    return tuple(out)


def build_requirements_met(reqs: list[str] | None = None) -> bool:
    """True if this interpreter already has every requirement of ``reqs``
    (default: pyproject.toml's ``[build-system] requires``) at a good
    version. Only ``name`` and ``name>=X`` are understood; anything else
    counts as not met."""
    import re
    from importlib import metadata

    if reqs is None:
        if sys.version_info >= (3, 11):
            import tomllib
        else:  # pragma: no cover
            import tomli as tomllib
        reqs = tomllib.loads((ROOT / "pyproject.toml").read_text())["build-system"]["requires"]
    for req in reqs:
        m = re.fullmatch(r"\s*([A-Za-z0-9_.-]+)\s*(?:>=\s*([0-9][0-9.]*))?\s*", req)
        if m is None:
            return False
        try:
            have = metadata.version(m.group(1))
        except metadata.PackageNotFoundError:
            return False
        if m.group(2) and _version_tuple(have) < _version_tuple(m.group(2)):
            return False
    return True


@task(help={"force": "rebuild the CFFI extensions even if up to date"})
def build(c, force=False):
    """Build the Python package and its CFFI extensions in place (editable install).

    pip builds in an isolated environment with pyproject's build requirements
    (setuptools >= 77 for the SPDX license field), fetched from the index:
    that works on a fresh machine whose own setuptools is older. When this
    interpreter already has them, the build reuses them (--no-build-isolation:
    faster, and works offline)."""
    isolation = "" if build_requirements_met() else " (isolated build environment)"
    flags = "--no-build-isolation " if not isolation else ""
    print(f"build: pip install -e .{isolation}", flush=True)
    with c.cd(str(ROOT)):
        c.run(f"{sys.executable} -m pip install -q {flags}-e ."
              f"{' --force-reinstall --no-deps' if force else ''}")


@task(help={
    "k": "only tests matching this pytest -k expression",
    "jobs": "parallel pytest workers (pytest-xdist); 0 = serial",
    "extra": "extra arguments passed to pytest verbatim",
    "fast": "the fast tier only: unit and differential tests on the host, no toolchain, process "
            "or simulator run (tests/conftest.py, test tiers); the full run is CI's",
})
def test(c, k="", jobs=2, extra="", fast=False):
    """Run the test suite (pytest; C, ARMv4T and 8051 targets included), or its fast tier."""
    args = [sys.executable, "-m", "pytest", "tests"]
    if fast:
        args.append("--fast")
    if jobs:
        args += ["-n", str(jobs)]
    if k:
        args += ["-k", repr(k)]
    if extra:
        args.append(extra)
    with c.cd(str(ROOT)):
        c.run(" ".join(args), pty=False)


@task
def lint(c):
    """Static checks: ruff and mypy on Python, strict warnings on every C compiler."""
    with c.cd(str(ROOT)):
        c.run(f"{sys.executable} -m ruff check attitude_c tests toolchain tasks.py bench", warn=False)
        c.run(f"{sys.executable} -m mypy attitude_c", warn=False)
        srcs = " ".join(str(p.relative_to(ROOT)) for p in sorted((ROOT / "csrc" / "src").glob("*.c")))
        strict = "-std=c99 -Wall -Wextra -Wpedantic -Werror -fsyntax-only -Icsrc/include"
        for cc in ("gcc", "clang"):
            if shutil.which(cc):
                for d in ("", "-DATT_REAL_F32"):
                    c.run(f"{cc} {strict} {d} {srcs}")
        format(c, check=True)


C_FORMAT_GLOBS = ("csrc/**/*.[ch]", "firmware/**/*.[ch]", "bench/*.c", "tests/*.c", "tests/s51/*.c",
                  "tests/consumer/*.c", "toolchain/*.[ch]")


def _c_format_files() -> list[str]:
    files: set[Path] = set()
    for g in C_FORMAT_GLOBS:
        files.update(ROOT.glob(g))
    return [str(p.relative_to(ROOT)) for p in sorted(files)]


@task(help={"check": "only report files that differ from .clang-format (exit 1 if any)"})
def format(c, check=False):
    """Apply .clang-format to every C source and header (csrc/, firmware/, C tests and benches)."""
    mode = "--dry-run --Werror" if check else "-i"
    with c.cd(str(ROOT)):
        c.run(f"clang-format {mode} " + " ".join(_c_format_files()))


@task
def clean(c):
    """Remove build outputs (build/, compiled extensions, caches)."""
    for p in [ROOT / "build", ROOT / "dist", ROOT / ".pytest_cache", ROOT / ".hypothesis"]:
        shutil.rmtree(p, ignore_errors=True)
    for pat in ("attitude_c/_att_*.so", "attitude_c/_att_*.c", "attitude_c/_att_*.o", "*.egg-info"):
        for p in ROOT.glob(pat):
            if p.is_dir():
                shutil.rmtree(p, ignore_errors=True)
            else:
                p.unlink()


# -- benchmarks ------------------------------------------------------------
# Each module bench/<name>.py defines TITLE and run(quick: bool) -> str (a
# Markdown section body). `invoke bench` runs them all (or --only NAME) and
# rewrites that module's section of docs/benchmarks.md, keeping the others.
BENCH_ORDER = ("host", "armv4t", "fixed", "tlc2543", "ad7927", "firmware", "aided", "chain", "link", "peers")


def _bench_modules() -> list[str]:
    present = {p.stem for p in (ROOT / "bench").glob("*.py") if not p.stem.startswith("_")}
    return [m for m in BENCH_ORDER if m in present] + sorted(present - set(BENCH_ORDER))


def _machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import os

    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, {platform.system()} {platform.release()}"


BENCH_PARTS = ROOT / "docs" / "bench"


#: The last line of every docs/bench/NAME.md: the SHA-256 of the text above it, written with
#: the figures, so that a hand edit shows (tests/test_bench_docs.py). Edit bench/NAME.py and
#: run `invoke bench --only NAME` instead.
BENCH_STAMP = "<!-- generated by `invoke bench`, do not edit: sha256 {} of the text above -->"


def stamped(text: str) -> str:
    """``text`` (ending in a newline) followed by its BENCH_STAMP line."""
    return text + BENCH_STAMP.format(hashlib.sha256(text.encode()).hexdigest()) + "\n"


def unstamped(text: str) -> str | None:
    """The text above a docs/bench file's stamp line, or None when the stamp is missing or
    does not match that text (the file was edited by hand)."""
    body = text.rstrip("\n").rpartition("\n")[0] + "\n"
    return body if stamped(body) == text else None


def write_bench_section(name: str, title: str, body: str, command: str) -> None:
    """Write docs/bench/NAME.md (one benchmark's latest figures) and reassemble the table."""
    BENCH_PARTS.mkdir(parents=True, exist_ok=True)
    stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    (BENCH_PARTS / f"{name}.md").write_text(stamped(
        f"## {title}\n\n*Machine:* {_machine()}  \n*Date:* {stamp}  \n"
        f"*Command:* `{command}`\n\n{body.strip()}\n"))
    assemble_bench_doc()


def bench_doc_text() -> str:
    """docs/benchmarks.md as assembled: header + every docs/bench/*.md in BENCH_ORDER, each
    without its stamp line (a part whose stamp does not match is taken as it stands)."""
    present = {p.stem: p for p in BENCH_PARTS.glob("*.md")}
    order = [n for n in BENCH_ORDER if n in present] + sorted(set(present) - set(BENCH_ORDER))
    texts = [present[n].read_text() for n in order]
    parts = [(unstamped(t) or t).strip() for t in texts]
    return ("# Benchmarks\n\n"
            "Latest figures of every benchmark of the project, one section per benchmark module "
            "(`bench/NAME.py`). Regenerate all of them with `invoke bench`, one with "
            "`invoke bench --only NAME`; each section gives the machine, the date and the command. "
            "The sections are docs/bench/NAME.md, each closed by a stamp of its text: they are "
            "written by the benchmarks only (`tests/test_bench_docs.py` fails on a hand edit), and "
            "the other pages refer to them rather than repeat their figures.\n\n"
            + "\n\n".join(parts) + "\n")


def assemble_bench_doc() -> None:
    """Write docs/benchmarks.md from docs/bench/*.md (bench_doc_text)."""
    BENCH_DOC.write_text(bench_doc_text())


class _NoData(Exception):
    """``--only`` a benchmark whose data is missing (its ``missing(data)`` says why)."""


@task(help={
    "only": "run only this benchmark module (bench/NAME.py); 'assemble' just rebuilds the table",
    "quick": "shorter runs (smoke test of the benchmark code, figures less precise)",
    "data": "a data folder for the benchmarks that take one (broad: an upstream BROAD data_mat/ folder; "
            "onav: onavdata 0.2.5's data folder)",
    "trials": "the benchmarks that take it (chain): only the BROAD trials whose names start so (comma-separated)",
    "budget": "the benchmarks that take it (chain): start no run after this many minutes (the table says so)",
})
def bench(c, only="", quick=False, data="", trials="", budget=""):
    """Run every benchmark and write the figures into docs/benchmarks.md."""
    import inspect

    if only == "assemble":  # just rebuild docs/benchmarks.md from docs/bench/*.md
        assemble_bench_doc()
        return
    mods = [only] if only else _bench_modules()
    failed: list[str] = []
    for name in mods:
        # one broken or unavailable benchmark must not lose the others' figures:
        # report it, keep its previous docs/bench/NAME.md, go on, fail at the end
        try:
            mod = importlib.import_module(f"bench.{name}")
            print(f"== bench {name}: {mod.TITLE}", flush=True)
            # a benchmark on data the project does not ship says what it needs through
            # missing(data) -> str | None: skipped in a full run, one clear line with --only
            why = mod.missing(data or None) if hasattr(mod, "missing") else None
            if why and not only:
                print(f"== bench {name}: skipped ({why})", flush=True)
                continue
            if why:
                raise _NoData(why)
            params = inspect.signature(mod.run).parameters
            extra = {k: v for k, v in (("data", data), ("trials", trials), ("budget", budget)) if v and k in params}
            body = mod.run(quick=quick, **extra)
        except _NoData as exc:  # --only a benchmark without its data: one line, no traceback
            from invoke.exceptions import Exit

            raise Exit(f"bench {name}: {exc}", code=1) from None
        except Exception as exc:  # noqa: BLE001 - any failure of one module
            import traceback

            traceback.print_exc()
            print(f"== bench {name}: FAILED ({type(exc).__name__}: {exc})", flush=True)
            failed.append(name)
            continue
        cmd = ("invoke bench" + (f" --only {name}" if only else "") + (" --quick" if quick else "")
               + "".join(f" --{k} {v}" for k, v in extra.items()))
        write_bench_section(name, mod.TITLE, body, cmd)
        print(body)
    assemble_bench_doc()
    print(f"wrote {BENCH_DOC.relative_to(ROOT)}")
    if failed:
        from invoke.exceptions import Exit

        raise Exit(f"benchmark(s) failed: {', '.join(failed)} (their previous sections were kept)",
                   code=1)
