"""Prove that ARM objects contain only instructions an ARM920T (ARMv4T) executes.

The check disassembles every object (``.o`` files or members of ``.a``
archives) with the target's objdump and accepts a mnemonic only if it is
in the ARMv4T ARM-state instruction set (an allow-list, so anything newer
is caught, not just the usual suspects). It reports, with object, function
and address:

* instructions the ARM920T lacks: ``blx``, ``clz``, ``ldrd``/``strd``,
  ``pld``, the v5TE DSP multiplies and saturating adds (``smulbb``,
  ``qadd``...), ``bkpt``, v6 and later (``ldrex``, ``rev``, ``uxtb``,
  ``movw``/``movt``, ``dmb``, ``udiv``...), VFP/NEON (``v*``, ``f*``,
  coprocessors p10/p11);
* returns and indirect jumps that rely on ARMv5 interworking: on ARMv4T,
  loading the pc (``pop {..., pc}``, ``ldm ... pc``, ``ldr pc, [sp]...``)
  or ``mov pc, rN`` never switches to Thumb state, so such a return into a
  Thumb caller crashes; ARMv4T code must return with ``bx``. Jump tables
  (``ldr pc, [pc, ...]``, ``add pc, pc, ...``) stay in ARM state and are
  accepted, and so are the PLT stubs GNU ld writes into a linked shared
  object or dynamic program (``.plt`` and ``NAME@plt``: ``ldr pc, [ip,
  #N]!``, ``ldr pc, [lr, #8]!``, and nothing else loading the pc): ld has no
  other ARM PLT (every ARMv4T dynamic binary has them); they jump in ARM
  state to the function the dynamic linker resolved, so on ARMv4T the
  callee must be ARM code: our own functions (built ``-marm``) and the
  board's libc/libm (docs/cross-build.md);
* Thumb code (the library is built with ``-marm``);
* ELF build attributes that claim a later architecture or an FPU
  (``Tag_CPU_arch`` other than v4T/v4, any ``Tag_FP_arch``/VFP arguments).

Command line: ``python -m toolchain.armv4t_check [--objdump X] FILE...``;
exit status 1 and one line per violation when something is wrong.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

__all__ = ["ARMV4T_BASES", "Armv4tCheckError", "Violation", "check_objects"]

#: ARMv4T ARM-state mnemonics in the unified syntax objdump prints, without
#: the optional "s" (set flags) suffix and condition code.
ARMV4T_BASES = frozenset(["and", "eor", "sub", "rsb", "add", "adc", "sbc", "rsc", "tst", "teq", "cmp", "cmn", "orr", "mov", "bic", "mvn", "lsl", "lsr", "asr", "ror", "rrx", "nop", "adr", "mul", "mla", "umull", "umlal", "smull", "smlal", "ldr", "ldrb", "ldrh", "ldrsb", "ldrsh", "ldrt", "ldrbt", "str", "strb", "strh", "strt", "strbt", "ldm", "ldmia", "ldmib", "ldmda", "ldmdb", "ldmfd", "ldmfa", "ldmed", "ldmea", "stm", "stmia", "stmib", "stmda", "stmdb", "stmfd", "stmfa", "stmed", "stmea", "push", "pop", "swp", "swpb", "b", "bl", "bx", "svc", "swi", "mrs", "msr", "cdp", "ldc", "stc", "mcr", "mrc"])

_CONDS = "eq|ne|cs|hs|cc|lo|mi|pl|vs|vc|hi|ls|ge|lt|gt|le|al"
_MNEM_RE = re.compile(r"^(?P<base>[a-z]+?)(?P<s>s)?(?P<cond>" + _CONDS + r")?$")

#: Why well-known non-v4T instructions are rejected (message text only; the
#: allow-list above decides).
_REASONS = {
    "blx": "BLX is ARMv5T",
    "clz": "CLZ is ARMv5T",
    "ldrd": "LDRD is ARMv5TE", "strd": "STRD is ARMv5TE", "pld": "PLD is ARMv5TE",
    "bkpt": "BKPT is ARMv5T", "mcrr": "MCRR is ARMv5TE", "mrrc": "MRRC is ARMv5TE",
    "cdp2": "CDP2 is ARMv5T", "ldc2": "LDC2 is ARMv5T", "stc2": "STC2 is ARMv5T",
    "mcr2": "MCR2 is ARMv5T", "mrc2": "MRC2 is ARMv5T",
    "qadd": "saturating arithmetic is ARMv5TE", "qsub": "saturating arithmetic is ARMv5TE",
    "qdadd": "saturating arithmetic is ARMv5TE", "qdsub": "saturating arithmetic is ARMv5TE",
    "ldrex": "exclusive access is ARMv6", "strex": "exclusive access is ARMv6",
    "rev": "REV is ARMv6", "uxtb": "extend instructions are ARMv6", "uxth": "extend instructions are ARMv6",
    "sxtb": "extend instructions are ARMv6", "sxth": "extend instructions are ARMv6",
    "movw": "MOVW is ARMv6T2", "movt": "MOVT is ARMv6T2", "ubfx": "bit-field instructions are ARMv6T2",
    "sbfx": "bit-field instructions are ARMv6T2", "bfi": "bit-field instructions are ARMv6T2",
    "bfc": "bit-field instructions are ARMv6T2", "mls": "MLS is ARMv6T2", "umaal": "UMAAL is ARMv6",
    "dmb": "barriers are ARMv7", "dsb": "barriers are ARMv7", "isb": "barriers are ARMv7",
    "sdiv": "hardware divide is ARMv7VE", "udiv": "hardware divide is ARMv7VE",
}


class Armv4tCheckError(RuntimeError):
    """The check itself could not run (tool missing, unreadable file)."""


@dataclass(frozen=True)
class Violation:
    obj: str
    function: str
    address: str
    insn: str
    reason: str

    def __str__(self) -> str:
        return f"{self.obj}: {self.function}+{self.address}: {self.insn}  -- {self.reason}"


def _reason_for(mnem: str) -> str:
    base = mnem.split(".")[0]
    for k, why in _REASONS.items():
        if base == k or (base.startswith(k) and _MNEM_RE.match(k + base[len(k):] or "")):
            return why
    if base.startswith(("v", "f")):
        return "floating-point/SIMD (VFP/NEON) instruction; the ARM920T has no FPU"
    if base.startswith(("smul", "smla", "smlal", "smulw", "smlaw")):
        return "DSP multiply is ARMv5TE"
    return "not an ARMv4T instruction"


#: The pc loads of GNU ld's ARM PLT: PLT0 ``ldr pc, [lr, #8]!`` (to the
#: dynamic linker's resolver), entries ``ldr pc, [ip, #N]!`` (through the GOT).
_PLT_LDR_PC_RE = re.compile(r"pc,\[(ip,#\d+|lr,#8)\]!")


def _is_plt(function: str) -> bool:
    return function == ".plt" or function.endswith("@plt")


def classify(mnem: str, operands: str, in_plt: bool = False) -> str | None:
    """Return why ``mnem operands`` is not acceptable ARMv4T code, or None if it
    is; ``in_plt``: the instruction is in a linker-generated PLT stub."""
    m = _MNEM_RE.match(mnem)
    if m is None or m.group("base") not in ARMV4T_BASES:
        # retry: a base ending in 's' such as "smulls" or "bics"
        ok = False
        for base in ARMV4T_BASES:
            if mnem.startswith(base):
                rest = mnem[len(base):]
                if re.fullmatch(r"s?(?:" + _CONDS + r")?", rest):
                    m2 = base
                    ok = True
                    break
        if not ok:
            return _reason_for(mnem)
        base = m2
    else:
        base = m.group("base")
    ops = operands.replace(" ", "")
    # Coprocessor instructions: p10/p11 are the VFP/NEON coprocessors.
    if base in {"cdp", "ldc", "stc", "mcr", "mrc"} and re.search(r"\bp1[01]\b", operands):
        return "coprocessor p10/p11 is VFP; the ARM920T has no FPU"
    # Returns / jumps that assume ARMv5 interworking (pc loaded without bx).
    regs_block = re.search(r"\{([^}]*)\}", ops)
    if ((base == "pop" or base.startswith("ldm")) and regs_block
            and re.search(r"(^|,)pc($|,)", regs_block.group(1))):
        return "loads pc with LDM/POP: does not interwork on ARMv4T (return with bx)"
    if base == "ldr" and ops.startswith("pc,") and not ops.startswith("pc,[pc"):
        if in_plt and _PLT_LDR_PC_RE.fullmatch(ops):
            return None  # GNU ld's PLT stub (see the module docstring)
        return "loads pc from memory: does not interwork on ARMv4T (use bx)"
    if base == "mov" and re.fullmatch(r"pc,(r\d+|lr|ip|sl|fp|sb)", ops):
        return "mov pc, reg: does not interwork on ARMv4T (use bx)"
    return None


_LINE_RE = re.compile(r"^\s*([0-9a-f]+):\s+(\S+)(?:\s+(.*?))?\s*$")
_FUNC_RE = re.compile(r"^[0-9a-f]+ <([^>]+)>:$")
_MEMBER_RE = re.compile(r"^(\S+):\s+file format (\S+)$")


def _disassemble(objdump: str, path: Path) -> str:
    proc = subprocess.run([objdump, "-d", "--no-show-raw-insn", str(path)],
                          capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise Armv4tCheckError(f"{objdump} -d {path} failed: {proc.stderr.strip()}")
    return proc.stdout


def check_disassembly(text: str, default_obj: str = "?") -> list[Violation]:
    """Violations in objdump ``-d --no-show-raw-insn`` output."""
    out: list[Violation] = []
    obj, func = default_obj, "?"
    for raw in text.splitlines():
        line = raw.rstrip()
        mm = _MEMBER_RE.match(line)
        if mm:
            obj, func = mm.group(1), "?"
            if "arm" not in mm.group(2) and "little" not in mm.group(2):
                out.append(Violation(obj, "-", "-", mm.group(2), "not a 32-bit ARM object"))
            continue
        fm = _FUNC_RE.match(line)
        if fm:
            func = fm.group(1)
            continue
        lm = _LINE_RE.match(line)
        if not lm:
            continue
        addr, mnem, operands = lm.group(1), lm.group(2), (lm.group(3) or "")
        if mnem.startswith("."):  # .word/.short/.byte: literal pools, data
            continue
        operands = operands.split(";")[0].split("@")[0].strip()
        why = classify(mnem.lower(), operands.lower(), in_plt=_is_plt(func))
        if why:
            out.append(Violation(obj, func, "0x" + addr, f"{mnem} {operands}".strip(), why))
    return out


def _readelf_for(objdump: str) -> str | None:
    cand = objdump[: -len("objdump")] + "readelf" if objdump.endswith("objdump") else "readelf"
    return shutil.which(cand)


def check_attributes(readelf: str, path: Path) -> list[Violation]:
    """Build attributes (``readelf -A``) must say v4T and no FPU."""
    proc = subprocess.run([readelf, "-A", str(path)], capture_output=True, text=True,
                          check=False)
    if proc.returncode != 0:
        raise Armv4tCheckError(f"{readelf} -A {path} failed: {proc.stderr.strip()}")
    out: list[Violation] = []
    member = path.name
    for line in proc.stdout.splitlines():
        s = line.strip()
        if s.startswith("File:"):
            member = s.split(":", 1)[1].strip()
        elif s.startswith("Tag_CPU_arch:"):
            arch = s.split(":", 1)[1].strip()
            if arch not in {"v4T", "v4"}:
                out.append(Violation(member, "-", "-", s, f"built for {arch}, not ARMv4T"))
        elif s.startswith(("Tag_FP_arch:", "Tag_Advanced_SIMD_arch:")):
            out.append(Violation(member, "-", "-", s, "object uses an FPU/SIMD unit"))
        elif s.startswith("Tag_ABI_VFP_args:") and "VFP registers" in s:
            out.append(Violation(member, "-", "-", s, "hard-float calling convention"))
        elif s.startswith("Tag_THUMB_ISA_use:") and "Thumb-2" in s:
            out.append(Violation(member, "-", "-", s, "Thumb-2 code"))
    return out


def check_objects(paths: Iterable[str | Path], objdump: str = "arm-linux-gnueabi-objdump") -> list[Violation]:
    """All violations in the given objects/archives (empty list = ARMv4T clean)."""
    tool = shutil.which(objdump)
    if tool is None:
        raise Armv4tCheckError(f"{objdump} not found; apt-get install binutils-arm-linux-gnueabi")
    readelf = _readelf_for(objdump)
    out: list[Violation] = []
    n = 0
    for p in map(Path, paths):
        if not p.exists():
            raise Armv4tCheckError(f"{p} does not exist")
        text = _disassemble(tool, p)
        syms = (subprocess.run([readelf, "-sW", str(p)], capture_output=True, text=True,
                               check=False).stdout
                if readelf else "")
        if re.search(r"\s\$t(\.\S*)?$", syms, re.MULTILINE):
            out.append(Violation(str(p), "-", "-", "$t", "contains Thumb code (library is built -marm)"))
        vs = check_disassembly(text, p.name)
        out.extend(vs)
        n += text.count("\n")
        if readelf:
            out.extend(check_attributes(readelf, p))
    if n == 0:
        raise Armv4tCheckError("nothing disassembled")
    return out


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="armv4t_check", description=__doc__.splitlines()[0])
    ap.add_argument("--objdump", default="arm-linux-gnueabi-objdump")
    ap.add_argument("files", nargs="+")
    a = ap.parse_args(argv)
    try:
        vs = check_objects(a.files, a.objdump)
    except Armv4tCheckError as exc:
        print(f"armv4t_check: {exc}", file=sys.stderr)
        return 2
    for v in vs:
        print(v)
    if vs:
        print(f"armv4t_check: {len(vs)} instruction(s) the ARM920T cannot execute", file=sys.stderr)
        return 1
    print(f"armv4t_check: {len(a.files)} file(s) are ARMv4T clean")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
