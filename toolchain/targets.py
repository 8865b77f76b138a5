"""Target definitions (toolchain/<name>.toml) and small build/run helpers.

One TOML file per target holds the compiler, flags, archiver, emulator and
the Debian packages that provide them; nothing toolchain-specific lives in
code. ``tasks.py`` and the tests both use this module.

    t = load("armv4t-bare")
    exe = t.build_program(["csrc/tests/test_quat.c"], "build/armv4t-bare/test_quat")
    out = t.run([exe])
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib  # type: ignore[no-redef]

ROOT = Path(__file__).resolve().parents[1]
TOOLCHAIN_DIR = ROOT / "toolchain"
CSRC = ROOT / "csrc"
INCLUDE = CSRC / "include"
BUILD = ROOT / "build"

#: Library sources that make up libattitude (portable C99).
LIB_SOURCES_DIR = CSRC / "src"
#: Platform code (HALs on an operating system's drivers): csrc/platform/<os>/
#: with src/*.c and include/attitude/*.h, built into the library of every
#: target of that ``os`` (e.g. the spidev HAL of the AD7927 on Linux).
PLATFORM_DIR = CSRC / "platform"


class ToolchainMissing(RuntimeError):
    """A tool of the target is not installed; the message says what to install."""


@dataclass
class Target:
    name: str
    kind: str  # "gcc" (gcc/clang-like driver) or "sdcc"
    os: str
    cc: str
    ar: str
    #: Every flag of the project's own compiles: ``strict_cflags + target_cflags``.
    cflags: list[str]
    ldflags: list[str] = field(default_factory=list)
    libs: list[str] = field(default_factory=list)
    run_cmd: list[str] = field(default_factory=list)
    apt: list[str] = field(default_factory=list)
    objdump: str | None = None
    #: Glob patterns (relative to the repository root) of the library sources
    #: built for this target; default: the whole portable library.
    lib_source_globs: list[str] = field(default_factory=lambda: ["csrc/src/*.c"])
    #: What `invoke cross-build` produces besides the static library.
    shared: bool = False          # libattitude.so (Linux targets)
    app: bool = False             # the attitude-rx program (needs POSIX threads and termios)
    app_libs: list[str] = field(default_factory=list)
    pic_flags: list[str] = field(default_factory=lambda: ["-fPIC"])
    #: How libattitude.so is linked (TOML ``shared_ldflags``, ``shared_libgcc``,
    #: ``shared_libs``): extra link flags; a command printing the path of a
    #: libgcc.a to link instead of the compiler's own runtime (empty: the
    #: compiler's); the libraries after it (default: ``libs``).
    shared_ldflags: list[str] = field(default_factory=list)
    shared_libgcc: list[str] = field(default_factory=list)
    shared_libs: list[str] = field(default_factory=list)
    #: Post-build checks by name (e.g. "armv4t": toolchain/armv4t_check.py).
    checks: list[str] = field(default_factory=list)
    #: The target itself (TOML ``cflags``: architecture, ABI, optimization): what
    #: ``make TARGET=NAME`` and cmake/NAME-toolchain.cmake pass too.
    target_cflags: list[str] = field(default_factory=list)
    #: The project's compile policy (TOML ``strict_cflags``: -std, warnings, -Werror).
    strict_cflags: list[str] = field(default_factory=list)

    def library_sources(self) -> list[Path]:
        """The library sources this target builds (sorted, de-duplicated)."""
        out: set[Path] = set()
        for pat in self.lib_source_globs:
            out.update(ROOT.glob(pat))
        return sorted(out)

    def platform_dir(self) -> Path | None:
        """csrc/platform/<os> when that folder exists (None on bare metal)."""
        d = PLATFORM_DIR / self.os
        return d if self.os != "none" and d.is_dir() else None

    def platform_sources(self) -> list[Path]:
        """The platform sources this target builds into its library (sorted)."""
        d = self.platform_dir()
        return sorted((d / "src").glob("*.c")) if d else []

    def platform_include_dirs(self) -> list[Path]:
        """Include directories of the platform code (headers as attitude/NAME.h)."""
        d = self.platform_dir()
        return [d / "include"] if d and (d / "include").is_dir() else []

    def tool(self, name: str) -> str:
        """A binutils tool of this toolchain (``readelf``, ``size``...) next to ``ar``."""
        if self.ar.endswith("-ar"):
            return self.ar[: -len("ar")] + name
        return name

    def shared_link_libs(self) -> list[str]:
        """What follows the objects on the link line of libattitude.so: the
        libgcc.a that ``shared_libgcc`` prints (if any), then ``shared_libs``."""
        if not self.shared_libgcc:
            return list(self.shared_libs)
        if shutil.which(self.shared_libgcc[0]) is None:
            raise ToolchainMissing(f"target {self.name}: libattitude.so links the libgcc of "
                                   f"{self.shared_libgcc[0]}, which is not found; {self.install_hint()}")
        proc = subprocess.run(self.shared_libgcc, capture_output=True, text=True, check=False)
        path = proc.stdout.strip()
        if proc.returncode != 0 or not Path(path).is_file():
            raise ToolchainMissing(f"target {self.name}: {' '.join(self.shared_libgcc)} gave no libgcc.a "
                                   f"({proc.stderr.strip() or path!r})")
        return [path, *self.shared_libs]

    # -- availability -----------------------------------------------------
    def tools(self) -> list[str]:
        tools = [self.cc, self.ar]
        if self.run_cmd:
            tools.append(self.run_cmd[0])
        if self.shared_libgcc:
            tools.append(self.shared_libgcc[0])
        return tools

    def missing_tools(self) -> list[str]:
        return [t for t in self.tools() if shutil.which(t) is None]

    def install_hint(self) -> str:
        return "apt-get install " + " ".join(self.apt)

    def require(self) -> None:
        missing = self.missing_tools()
        if missing:
            raise ToolchainMissing(
                f"target {self.name}: {', '.join(missing)} not found; {self.install_hint()}"
            )

    # -- building ---------------------------------------------------------
    def build_dir(self) -> Path:
        return BUILD / self.name

    def compile_cmd(self, src: Path | str, obj: Path | str, defines: Sequence[str] = (),
                    extra_cflags: Sequence[str] = (), include_dirs: Sequence[Path | str] = ()) -> list[str]:
        incs = [f"-I{d}" for d in (INCLUDE, *include_dirs)]
        defs = [f"-D{d}" for d in defines]
        return [self.cc, *self.cflags, *incs, *defs, *extra_cflags, "-c", str(src), "-o", str(obj)]

    def build_program(self, sources: Iterable[Path | str], out: Path | str, *,
                      defines: Sequence[str] = (), extra_cflags: Sequence[str] = (),
                      include_dirs: Sequence[Path | str] = (), with_lib: bool = True,
                      lib_sources: Sequence[Path | str] | None = None) -> Path:
        """Compile ``sources`` (plus the library sources if ``with_lib``) into one program.

        gcc-kind targets compile and link in one driver call; the output is
        an executable. sdcc targets compile each file to a .rel and link an
        Intel-hex image ``out`` (suffix .ihx); the main file must come first.
        """
        self.require()
        out = Path(out)
        out.parent.mkdir(parents=True, exist_ok=True)
        srcs = [Path(s) for s in sources]
        if with_lib:
            libsrc = [Path(s) for s in (lib_sources if lib_sources is not None
                                        else sorted(LIB_SOURCES_DIR.glob("*.c")))]
            srcs += [s for s in libsrc if s not in srcs]
        incs = [f"-I{d}" for d in (INCLUDE, *include_dirs)]
        defs = [f"-D{d}" for d in defines]
        if self.kind == "sdcc":
            objdir = out.parent / (out.stem + ".objs")
            objdir.mkdir(parents=True, exist_ok=True)
            rels = []
            for s in srcs:
                rel = objdir / (s.stem + ".rel")
                _run([self.cc, *self.cflags, *incs, *defs, *extra_cflags, "-c", str(s), "-o", str(rel)])
                rels.append(str(rel))
            ihx = out.with_suffix(".ihx")
            _run([self.cc, *self.cflags, *self.ldflags, *extra_cflags, *rels, "-o", str(ihx)])
            return ihx
        cmd = [self.cc, *self.cflags, *incs, *defs, *extra_cflags, *map(str, srcs),
               "-o", str(out), *self.ldflags, *self.libs]
        _run(cmd)
        return out

    def run(self, argv: Sequence[str | Path], *, input: bytes | None = None,
            timeout: float = 600, check: bool = True, extra_run_args: Sequence[str] = ()) -> subprocess.CompletedProcess:
        """Run a program built for this target (through its emulator if any)."""
        cmd = [*self.run_cmd, *extra_run_args, *map(str, argv)]
        proc = subprocess.run(cmd, check=False, input=input, capture_output=True, timeout=timeout)
        if check and proc.returncode != 0:
            raise subprocess.CalledProcessError(proc.returncode, cmd, proc.stdout, proc.stderr)
        return proc


@dataclass(frozen=True)
class AppOptional:
    """One optional dependency of attitude-rx (toolchain/app/optional.toml)."""

    name: str
    define: str
    header: str
    symbol: str
    libs: tuple[str, ...]
    apt: str


    def probe_source(self) -> str:
        """The probe: a program that includes the header and takes the symbol's address (the
        Makefile and CMakeLists.txt write the same one)."""
        return f"#include <{self.header}>\nint main(void)\n{{\n    return (int)(long)&{self.symbol};\n}}\n"


def app_optional() -> list[AppOptional]:
    """attitude-rx's optional dependencies, from toolchain/app/optional.toml."""
    d = tomllib.loads((TOOLCHAIN_DIR / "app" / "optional.toml").read_text())
    return [AppOptional(name=k, define=v["define"], header=v["header"], symbol=v["symbol"],
                        libs=tuple(v["libs"]), apt=v["apt"]) for k, v in d.items()]


def _run(cmd: list[str]) -> None:
    proc = subprocess.run(cmd, check=False, capture_output=True, text=True)
    if proc.returncode != 0:
        raise subprocess.CalledProcessError(proc.returncode, cmd, proc.stdout, proc.stderr)


def names() -> list[str]:
    return sorted(p.stem for p in TOOLCHAIN_DIR.glob("*.toml"))


def load(name: str) -> Target:
    path = TOOLCHAIN_DIR / f"{name}.toml"
    if not path.exists():
        raise ValueError(f"unknown target {name!r}; known targets: {', '.join(names())}")
    d = tomllib.loads(path.read_text())
    cc = os.environ.get(f"ATT_CC_{name.upper().replace('-', '_')}", d["cc"])
    strict, target = list(d.get("strict_cflags", [])), list(d.get("cflags", []))
    return Target(
        name=d["name"], kind=d["kind"], os=d["os"], cc=cc, ar=d["ar"],
        cflags=strict + target, target_cflags=target, strict_cflags=strict,
        ldflags=list(d.get("ldflags", [])),
        libs=list(d.get("libs", [])), run_cmd=list(d.get("run", [])),
        apt=list(d.get("apt", [])), objdump=d.get("objdump"),
        lib_source_globs=list(d.get("lib_sources", ["csrc/src/*.c"])),
        shared=bool(d.get("shared", False)), app=bool(d.get("app", False)),
        app_libs=list(d.get("app_libs", [])), pic_flags=list(d.get("pic_flags", ["-fPIC"])),
        checks=list(d.get("checks", [])),
        shared_ldflags=list(d.get("shared_ldflags", [])),
        shared_libgcc=list(d.get("shared_libgcc", [])),
        shared_libs=list(d.get("shared_libs", d.get("libs", []))),
    )
