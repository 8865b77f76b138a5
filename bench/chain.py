"""Real recordings through the whole aided chain (issue 26).

Each BROAD trial (D. Laidig, M. Caruso, A. Cereatti, T. Seel, Data 6(7), 2021,
doi:10.3390/data6070072, CC BY 4.0; the trials in ../shared/data/broad) is taken at the
aided firmware's sampling instants (``toolchain.firmware.AIDED``'s period, linear
interpolation) and converted to the board's 12-bit codes (attitude_c.sim.board_codes:
the adxl335 and hmc1043-ad623 presets' resolutions, a ±2000 °/s gyro conditioned to 0.9
of the ADC half-range; round to nearest, clipped at the range and the rails). The codes are
served by the TLC2543 model (FW_SIM_DATA: the simulator interface's input file) to the
aided firmware image in ``s51 -t C52``; its link v2 bytes go over a pty to attitude-rx
(host build; ARMv4T under qemu-arm on the first trial) with ``--estimator auto`` and the
configuration written from the same channels; its JSON lines' quaternions are scored with
BROAD's metric (attitude_c.broad, as bench/broad.py) against the reference at the board's
instants. Beside it, the library's filter (att_ahrs, double, defaults) run directly on the
same converted codes with the same decimation (NULL where the board sends no
accelerometer or magnetometer record), and on the unquantized samples.

s51 runs in lockstep with attitude-rx (toolchain.aided_chain.Relay): an acknowledgement
reaches the firmware within a bounded simulated time however loaded the machine, so no
sample is lost to the host's lateness. Whole trials by default; ``--quick`` runs
QUICK_SECONDS of every trial from QUICK_LEAD before its movement phase. s51 runs slower than
real time (about 3 x on the shared 2-core machine): ``--trials`` picks trials by name
prefix (``invoke bench --only chain --trials 01,07``), and the table says which ran.
"""

from __future__ import annotations

import hashlib
import os
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
TITLE = "The aided chain on BROAD: firmware (s51) → link v2 → pty → attitude-rx, against the library filter"
#: --quick: each trial from QUICK_LEAD s before its first movement sample (rest: the filter
#: settles), for QUICK_SECONDS
QUICK_LEAD, QUICK_SECONDS = 10.0, 35.0
COLUMNS = ("chain", "direct", "unquantized", "vqf")
#: finished runs, kept between invocations (a long benchmark resumes where it stopped)
RUNS = ROOT / "build" / "bench_chain" / "runs"


def _recording(tr: Any, quick: bool) -> tuple[Any, dict[str, Any]]:
    """The trial (or its --quick excerpt) as the board's codes, and the direct filters' figures."""
    from vqf import VQF

    from attitude_c import broad
    from attitude_c.sim.board_codes import values
    from toolchain import aided_chain as ac

    start = max(0.0, float(np.flatnonzero(tr.movement)[0]) / tr.rate - QUICK_LEAD) if quick else 0.0
    rec = ac.recording(tr, start=start, duration=QUICK_SECONDS if quick else None)
    out: dict[str, Any] = {"name": tr.name, "start": start, "seconds": rec.n * rec.period, "clipped": rec.clipped()}
    for k in ("direct", "unquantized"):
        out[k] = broad.errors(ac.direct(rec, quantized=k == "direct"), rec.quat, rec.movement).total
    si = [np.ascontiguousarray(values(rec.codes[k], rec.channels[k])) for k in ("gyro", "acc", "mag")]
    out["vqf"] = broad.errors(np.asarray(VQF(rec.period).updateBatch(*si)["quat9D"]), rec.quat, rec.movement).total
    return rec, out


def _run_file(rec: Any, name: str, build: str, image: Any, app: Path) -> Path:
    """Where a run is kept: named by what decides it — the firmware's image, the codes it serves
    and attitude-rx's executable (a library change makes a new one, so the run is made again);
    the table also recomputes max diff against the library of the moment."""
    h = hashlib.sha256(image.ihx.read_bytes())
    h.update(app.read_bytes())
    for k in ("gyro", "acc", "mag"):
        h.update(np.ascontiguousarray(rec.codes[k], dtype=np.int64).tobytes())
    return RUNS / f"{name}-{build}-{h.hexdigest()[:16]}.npz"


def _commit() -> str:
    import subprocess

    r = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True, check=False)
    return r.stdout.strip() or "unknown"


def _chain_run(rec: Any, name: str, build: str, cmd: list[str], build_dir: Path) -> dict[str, Any]:
    """The chain's run of ``rec``: kept from an earlier run of the same firmware image on the same
    codes (``build/bench_chain/runs``, written then renamed), else run now and kept."""
    from toolchain import aided_chain as ac

    img = ac.chain_image(rec, build_dir / f"{name}_{build}")
    path = _run_file(rec, name, build, img, Path(cmd[-1]))
    if path.exists():
        with np.load(path) as z:
            print(f"   chain: {name} ({build}): kept from the run at {z['commit']}", flush=True)
            return {k: z[k].item() if z[k].ndim == 0 else z[k] for k in z.files}
    print(f"   chain: {name} ({build}) ...", flush=True)
    run = ac.run_chain(rec, cmd, build_dir / f"{name}_{build}", image=img)
    print(f"   chain: {name} ({build}) done: {run.sim_seconds:.0f} s simulated in {run.wall_seconds:.0f} s", flush=True)
    got: dict[str, Any] = {"q": run.q, "lost": np.asarray(run.lost, np.int64), "once": run.delivered_once(rec.n),
           "records": run.stats.get("records", 0), "frames": run.frames, "wall": run.wall_seconds,
           "sim": run.sim_seconds, "commit": _commit()}
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".part.npz")
    np.savez(tmp, **got)
    os.replace(tmp, path)
    return got


def _chain(rec: Any, name: str, build: str, cmd: list[str], build_dir: Path) -> dict[str, Any]:
    """One run through the chain with attitude-rx's ``build``: its figures against the direct filter."""
    from attitude_c import broad
    from toolchain import aided_chain as ac

    run = _chain_run(rec, name, build, cmd, build_dir)
    lost = [int(i) for i in run["lost"]]
    q_same = ac.direct(rec, lost=lost)  # a lost sample held as attitude-rx holds it (none expected)
    return {"chain": broad.errors(run["q"], rec.quat, rec.movement).total,
            "diff": float(np.degrees(np.nanmax(broad.error_angles(run["q"], q_same)[0]))),
            "once": bool(run["once"]), "lost": len(lost), "records": int(run["records"]),
            "frames": int(run["frames"]), "wall": float(run["wall"]), "sim": float(run["sim"]),
            "commit": str(run["commit"])}


def _row(r: dict[str, Any], build: str) -> str:
    c = r[build]
    once = "yes" if c["once"] else f"**no: {c['lost']} lost**"
    return (f"| {r['name']} | {build} | {r['start']:.1f} + {r['seconds']:.1f} | {c['chain']:.3f} | {r['direct']:.3f} | "
            f"{r['unquantized']:.3f} | {r['vqf']:.3f} | {c['diff']:.1e} | {once} ({c['records']}, {c['frames']}) | "
            f"{c['sim']:.0f} / {c['wall']:.0f} | {c['commit']} |")


def _selected(trials: str) -> list[Any]:
    from attitude_c import broad

    every = list(broad.iter_trials())
    want = [t.strip() for t in trials.split(",") if t.strip()]
    picked = [tr for tr in every if not want or any(tr.name.startswith(w) for w in want)]
    if not picked:
        raise ValueError(f"trials: no BROAD trial name starts with any of {want}")
    return picked


def _header(quick: bool, n: int, total: int, budget: str) -> str:
    from attitude_c.sim.board_codes import board_channels
    from toolchain import firmware as tool

    cfg = tool.AIDED
    which = (f"{QUICK_SECONDS:.0f} s of each from {QUICK_LEAD:.0f} s before its movement phase "
             "(`--quick`; *from + s*: the excerpt's start and length)" if quick else "whole")
    cut = f" whose run started within `--budget {budget}` minutes" if budget else ""
    some = (f"**{n} of the {total} shipped trials**: those of `--trials`{cut} (`invoke bench --only chain` runs "
            "them all)" if n < total else f"all {total} shipped trials")
    return (f"Firmware: `toolchain.firmware.AIDED` (gyros every {cfg.period_ticks}/{tool.TICK_HZ} s, accelerometer "
            f"every {cfg.acc_every}, magnetometer every {cfg.mag_every} samples, link v2 at {cfg.baud} baud), "
            "sim image with the data-driven TLC2543 model, s51 in lockstep with attitude-rx (an acknowledgement "
            f"reaches the firmware at most {tool.LOCKSTEP_BOUND_S * 1e3:.1f} ms of simulated time after its frame). "
            "Codes (round to nearest about 2048): "
            + "; ".join(f"{c.name} {c.lsb:.4g} {c.unit} per code, clipped at ±{c.clip:.4g} {c.unit}"
                        for c in board_channels().values())
            + f". Trials: {some}, {which}.")


LEGEND = ("BROAD total error (RMS over the movement phase, deg) of: the chain (attitude-rx's lines); the library "
          "filter run directly on the same codes (direct); on the unquantized samples at the same instants "
          "(unquantized); VQF (`VQF(period)`, defaults, 9-D, `updateBatch`) on the same codes converted as "
          "attitude-rx converts them (VQF). *max diff*: largest angle between the chain's and the direct filter's attitude over "
          "all samples (deg; ~1e-6 is arccos's resolution near 0, i.e. equal). *once*: every sample printed "
          "once in order, no loss report, no duplicate (records attitude-rx received, BOOT and CHANNELS "
          "included; link v2 frames, each answered before s51 ran on). *sim / wall*: seconds of simulated "
          "time and of wall time the s51 run took. *run at*: the commit the s51 run was made at (a run is kept in "
          "build/bench_chain/runs, named by the hash of the firmware image, the codes and attitude-rx's executable, "
          "and reused by a later invocation; *max diff* is computed again at every table against the library of the table's commit).")


def _summary(rows: list[dict[str, Any]]) -> list[str]:
    val = {k: [r["host"]["chain"] if k == "chain" else r[k] for r in rows] for k in COLUMNS}
    once = "all" if all(r[b]["once"] for r in rows for b in ("host", "armv4t") if b in r) else "**not all**"
    mean = " | ".join(f"{np.mean(val[k]):.3f}" for k in COLUMNS[1:])
    worst = " | ".join(f"{max(val[k]):.3f}" for k in COLUMNS[1:])
    return [(f"| **mean ({len(rows)} trials)** | host | | **{np.mean(val['chain']):.3f}** | {mean} | "
             f"{max(r['host']['diff'] for r in rows):.1e} | {once} | | |"),
            f"| **worst trial** | host | | **{max(val['chain']):.3f}** | {worst} | | | | |"]


def _runs(picked: list[Any], quick: bool, cmds: dict[str, list[str]], build_dir: Path,
          budget: float) -> list[dict[str, Any]]:
    """The first trial with the ARMv4T build, then every trial with the host build; two at a time
    (lockstep: a run's figures do not depend on the machine's load). No run starts after
    ``budget`` minutes (0: no limit); the rows are the trials whose host run was made."""
    import threading
    import time

    t0, lock, rows = time.monotonic(), threading.Lock(), {}
    units = [(picked[0], "armv4t")] + [(tr, "host") for tr in picked]  # the ARMv4T run first: a budget never drops it

    def one(unit: tuple[Any, str]) -> None:
        tr, build = unit
        if budget and time.monotonic() - t0 > 60.0 * budget:
            print(f"   chain: {tr.name} ({build}) not started: the {budget:g}-minute budget is spent", flush=True)
            return
        rec, out = _recording(tr, quick)
        res = _chain(rec, tr.name, build, cmds[build], build_dir)
        with lock:
            rows.setdefault(tr.name, out)[build] = res

    with ThreadPoolExecutor(max_workers=min(2, os.cpu_count() or 1)) as pool:
        list(pool.map(one, units))
    return [rows[tr.name] for tr in picked if "host" in rows.get(tr.name, {})]


def run(quick: bool, trials: str = "", budget: str = "") -> str:
    from attitude_c import broad
    from toolchain import targets
    from toolchain.tasks.cross import cross_build_target

    build_dir = ROOT / "build" / "bench_chain"
    arm_t = targets.load("armv4t")
    cmds = {"host": [str(cross_build_target("host", out=build_dir / "host")["app"])],
            "armv4t": [*arm_t.run_cmd, str(cross_build_target("armv4t", out=build_dir / "armv4t")["app"])]}
    picked = _selected(trials)
    rows = _runs(picked, quick, cmds, build_dir, float(budget or 0))
    if not rows:
        raise RuntimeError("no trial ran within the budget")
    lines = [_header(quick, len(rows), len(list(broad.iter_trials())), budget), "", LEGEND, "",
             ("| trial | attitude-rx | from + s | chain | direct | unquantized | VQF | max diff | once (records, frames) "
             "| sim / wall s | run at |"), "|---|---|---:|---:|---:|---:|---:|---:|---|---:|---|"]
    lines += [_row(r, b) for r in rows for b in ("host", "armv4t") if b in r]
    lines += _summary(rows)
    lines += ["", "Codes clipped (values at a channel's limit, these trials): " + ", ".join(
        f"{k} {sum(r['clipped'][k] for r in rows)}" for k in ("gyro", "acc", "mag")) + "."]
    return "\n".join(lines)
