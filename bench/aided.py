"""The aided AT89S52 board: its sampling plan, chosen from the 8051's CPU load in s51 and
the attitude filter's accuracy on BROAD with the accelerometer and magnetometer decimated.

CPU load. The ``bench`` image of the aided firmware (production code, pins and RAM
layout; toolchain/firmware.py ``Config(board="aided9")``) runs in ``s51 -t C52`` with
libattitude's C link v2 receiver on the pty (``toolchain.firmware.run_v2``). The main
loop adds the machine cycles of every iteration that did nothing (no byte in or out, no
poll result but NONE/IDLE, no scan) to an idle counter; busy = 1 - idle / total, the total
being the firmware's Timer 0 ticks from its first iteration to the end (x 256 cycles). In
s51 nothing drives P1, so EOC reads "done" at once: a scan is the driver's own cost (on a
board each conversion also waits up to 10 us). s51 runs in lockstep with the receiver
(``run_v2(..., lockstep=True)``: every answer reaches the firmware within
``toolchain.firmware.LOCKSTEP_BOUND_S`` of simulated time), so the figures are the
firmware's own, not the machine's load (a host answering in wall time, as before, showed a
loaded machine's lateness, stretched, as records waiting in the ring and lost).

Accuracy. BROAD (D. Laidig, M. Caruso, A. Cereatti, T. Seel, Data 6(7), 2021,
doi:10.3390/data6070072, CC BY 4.0), the trials in ../shared/data/broad: each trial taken
at the board's sampling instants (every 3rd or 6th sample of its 285.7 Hz: 95.2 or 47.6 Hz,
point samples as the board takes them), then fed to ``att_ahrs`` (defaults) one sample at a
time with the accelerometer and magnetometer only in every k-th sample (NULL otherwise:
``att_ahrs_update``'s "no accelerometer / six-axis this sample"), as the board's groups
deliver them. Figures: BROAD's total error, RMS per trial, mean and worst over the trials.

Gyro oversampling (``Config.gyro_oversample``, docs/firmware.md): CPU rows of the images
that convert the gyros 2 or 4 times per sample (sent as sums or as rounded means), and the
direct filter of the aided chain (``toolchain.aided_chain.direct``) on the trials converted
to the board's codes with 1, 2 or 4 gyro conversions per sample; and which channels'
quantization costs what (each channel quantized alone).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
TITLE = "Aided AT89S52 board: CPU load per sampling plan (s51) and the filter's accuracy with decimated aiding (BROAD)"

#: (gyro period in ticks of 1/3600 s, acc every, mag every) of the plans measured (at 115200
#: baud; the default plan at 57600 too)
PLANS = ((72, 1, 1), (72, 2, 2), (72, 4, 4), (36, 1, 1), (36, 2, 2), (36, 2, 4), (36, 4, 4))
#: BROAD sample steps (285.7 Hz / step: about the board's gyro rates) and (acc, mag) decimations
STEPS = (6, 3)
KS = ((1, 1), (2, 2), (2, 4), (4, 4), (8, 8))


def cpu_load(tool: Any, build_dir: Path, plan: tuple[int, int, int], baud: int, records: int,
             sr: bool = False, ovs: int = 1, mean: bool = False) -> dict[str, Any]:
    """One plan's bench run (``sr``: with the magnetometer's set/reset; ``ovs``: gyro
    conversions per sample, sent as their sum or, ``mean``, their rounded mean): busy
    fraction, delivered rates, stack."""
    period, acc, mag = plan
    cfg = dataclasses.replace(tool.AIDED, baud=baud, period_ticks=period, acc_every=acc, mag_every=mag, mag_sr=sr,
                              gyro_oversample=ovs, gyro_mean=mean)
    img = tool.build(build_dir, cfg, kind="bench", sim_samples=records,
                     name=f"aided_{baud}_{period}_{acc}_{mag}" + ("_sr" if sr else "") + (f"_x{ovs}" if ovs > 1 else "")
                     + ("_mean" if mean else ""))
    res = tool.run_v2(img, "c", timeout=900, lockstep=True)
    b = res.bench
    total = ((b["ticks"] - b["tick0"]) & 0xFFFF) * 256  # ticks since the first iteration, in cycles
    seconds = total / tool.MACHINE_HZ
    per_sample = 1 + 1 / acc + 1 / mag  # records per sample: gyro + accelerometer + magnetometer
    return {"busy": 1.0 - b["idle"] / total, "taken": res.stats["samples"] / seconds,
            "records": res.stats["accepted"] / seconds, "wanted": tool.TICK_HZ / period * per_sample,
            "overrun": res.stats["overrun_pending"], "scan": b["scan_sum"] / b["scans"], "scan_max": b["scan_max"],
            "max_sp": res.max_sp, "stack_start": img.stack_start, "bad_frames": res.receiver["bad_frames"]}


def profile(tool: Any, build_dir: Path, records: int) -> dict[str, float]:
    """Where the default plan's cycles go: the profile image (-DFW_PROFILE, firmware/sim/hooks.h)
    times every poll of the sender and every sink call (its timestamps inflate the load, so
    the busy figure comes from the plain bench image)."""
    img = tool.build(build_dir, tool.AIDED, kind="bench", sim_samples=records, name="aided_profile",
                     extra_defines=["FW_PROFILE"])
    res = tool.run_v2(img, "c", timeout=900, lockstep=True)
    b, n = res.bench, res.stats["accepted"]
    return {"per_frame": n / max(1, b["nframe"]), "bytes": b["nsend"] / n, "poll": b["psend"] / b["nsend"],
            "rx_bytes": b["nrx"] / n, "sink": b["prx"] / max(1, b["nrx"]), "scan": b["scan_sum"] / n,
            "idle_polls": b["pother"] / n}


def run_decimated(tr: Any, step: int, k: tuple[int, int]) -> np.ndarray:
    """att_ahrs on the trial's every ``step``-th sample, with the accelerometer in every
    k[0]-th of those and the magnetometer in every k[1]-th (a multiple of k[0])."""
    from attitude_c.ahrs_filter import Ahrs

    g = np.ascontiguousarray(tr.gyr[::step], dtype=np.float64)
    a = np.ascontiguousarray(tr.acc[::step], dtype=np.float64)
    m = np.ascontiguousarray(tr.mag[::step], dtype=np.float64)
    f = Ahrs(rate=tr.rate / step)
    ffi, lib, s = f._ffi, f._lib, f._s  # one sample at a time, NULL where the board sends no aiding
    out = np.empty((g.shape[0], 4))
    q = ffi.new("att_real[4]")
    dt = step / tr.rate
    ptr = lambda x, i: ffi.cast("att_real *", ffi.from_buffer(x[i]))  # noqa: E731
    for i in range(g.shape[0]):
        st = lib.att_ahrs_update(s, ptr(g, i), ptr(a, i) if i % k[0] == 0 else ffi.NULL,
                                 ptr(m, i) if i % k[1] == 0 else ffi.NULL, dt, q)
        if st != 0:
            raise RuntimeError(f"{tr.name}: att_ahrs_update failed at sample {i} (status {st})")
        out[i] = list(q)
    return out


def _stats(figs: dict[Any, list[float]]) -> dict[Any, dict[str, float]]:
    return {key: {"mean": float(np.mean(v)), "worst": float(np.max(v)), "n": len(v)} for key, v in figs.items()}


def broad_accuracy(quick: bool) -> dict[tuple[int, tuple[int, int]], dict[str, float]]:
    """(step, (acc every, mag every)) -> mean and worst total error (deg) over the BROAD trials here."""
    from attitude_c import broad

    trials = list(broad.iter_trials())
    if quick:
        trials = trials[:3]
    figs: dict[tuple[int, tuple[int, int]], list[float]] = {}
    for tr in trials:
        for step in STEPS:
            for k in KS:
                q = run_decimated(tr, step, k)
                e = broad.errors(q, tr.quat[::step], tr.movement[::step])
                figs.setdefault((step, k), []).append(e.total)
    return _stats(figs)


#: (acc every, mag every, gyro conversions per sample, sent as their rounded mean) of the
#: oversampling accuracy rows
OVS_PLANS = ((1, 1, 1, False), (1, 1, 2, False), (1, 1, 4, False), (1, 1, 2, True), (1, 1, 4, True),
             (4, 4, 1, False), (4, 4, 2, False))
#: the CPU rows with the gyros oversampled: ((period, acc every, mag every), conversions, mean)
OVS_CPU = (((72, 1, 1), 2, False), ((72, 1, 1), 4, False), ((72, 4, 4), 2, False), ((72, 1, 1), 2, True),
           ((72, 1, 1), 4, True))
#: which channels are quantized in the "where quantization costs" rows (the others: SI values)
QUANT_SETS = (("none", ()), ("gyro only", ("gyro",)), ("acc only", ("acc",)), ("mag only", ("mag",)),
              ("all", ("gyro", "acc", "mag")))


def code_accuracy(tool: Any, quick: bool) -> tuple[dict[Any, dict[str, float]], dict[Any, dict[str, float]]]:
    """The direct filter (toolchain.aided_chain.direct: what the chain computes) on the BROAD
    trials converted to the board's codes at the default plan's period: (1) per OVS_PLANS row,
    quantized, the gyros oversampled; (2) per QUANT_SETS row, only those channels quantized."""
    from attitude_c import broad
    from attitude_c.sim.board_codes import values
    from toolchain import aided_chain

    trials = list(broad.iter_trials())[:3 if quick else None]
    ovs: dict[Any, list[float]] = {}
    quant: dict[Any, list[float]] = {}
    for tr in trials:
        for ka, km, n, mean in OVS_PLANS:
            cfg = dataclasses.replace(tool.AIDED, acc_every=ka, mag_every=km, gyro_oversample=n, gyro_mean=mean)
            rec = aided_chain.recording(tr, cfg)
            ovs.setdefault((ka, km, n, mean), []).append(broad.errors(aided_chain.direct(rec, cfg), rec.quat,
                                                                rec.movement).total)
        rec = aided_chain.recording(tr)
        for label, chans in QUANT_SETS:
            si = {k: values(rec.codes[k], rec.channels[k]) if k in chans else rec.si[k] for k in rec.si}
            q = aided_chain.direct(dataclasses.replace(rec, si=si), quantized=False)
            quant.setdefault(label, []).append(broad.errors(q, rec.quat, rec.movement).total)
    return _stats(ovs), _stats(quant)


def _sent(n: int, mean: bool) -> str:
    return "1" if n == 1 else f"{n}, {'mean' if mean else 'sum'}"


def _cpu_table(tool: Any, cpu: dict[Any, dict[str, Any]], records: int) -> list[str]:
    lines = [f"CPU load in s51 (C52 core, {records} sample records acknowledged per run):", "",
             "| gyros | gyro conversions per sample | acc every | mag every | mag set/reset | records/s wanted | "
             "baud | busy | records/s delivered |", "|---:|---:|---:|---:|:---:|---:|---:|---:|---:|"]
    for ((p, ka, km), baud, sr, n, mean), c in cpu.items():
        lines.append(f"| {tool.TICK_HZ / p:.0f} Hz | {_sent(n, mean)} | {ka} | {km} | {'yes' if sr else 'no'} | "
                     f"{c['wanted']:.1f} | {baud} | {100 * c['busy']:.1f} % | {c['records']:.1f} |")
    return lines


def _ovs_lines(tool: Any, cpu: dict[Any, dict[str, Any]], ovs: dict[Any, dict[str, float]],
               quant: dict[Any, dict[str, float]], prod2: Any) -> list[str]:
    """The gyro oversampling section: image, accuracy per N, where quantization costs."""
    sp = max(c["max_sp"] for (_, _, _, n, _), c in cpu.items() if n > 1)
    lines = ["### Gyro oversampling (`gyro_oversample`, docs/firmware.md)", "",
             (f"Image with two gyro conversions per sample (`gyro_oversample=2`, the default plan otherwise): flash "
              f"{prod2.flash}, RAM {prod2.ram_static} static, stack from 0x{prod2.stack_start:02X}; highest SP seen "
              f"in s51 over the oversampled runs above 0x{sp:02X}. The CPU rows with 2 or 4 conversions sent as "
              "sums show the link, not the CPU, as the limit: the sums (above 4095) do not fit link v2's packed "
              "12-bit DATA frames and travel one record per RAW frame (docs/link.md), so records/s delivered "
              "fall short of those wanted with the accelerometer and magnetometer in every sample; sent as "
              "their rounded mean (`gyro_mean=True`) the stream stays plain and packed."), "",
             (f"The direct filter (`toolchain.aided_chain.direct`, what the chain computes) on the BROAD trials "
              f"(citation below) converted to the board's codes at {tool.TICK_HZ / tool.AIDED.period_ticks:.0f} "
              "samples/s (`attitude_c.sim.board_codes`), the gyros converted n times per sample at the "
              "sub-interval midpoints and summed (divided by n as attitude-rx divides) or sent as their "
              "rounded mean code; total error, RMS per "
              f"trial, deg; {next(iter(ovs.values()))['n']} trials:"), "",
             "| acc every | mag every | gyro conversions per sample, sent as | mean | worst |",
             "|---:|---:|---:|---:|---:|"]
    lines += [f"| {ka} | {km} | {_sent(n, m)} | {a['mean']:.3f} | {a['worst']:.3f} |"
              for (ka, km, n, m), a in ovs.items()]
    lines += ["", "Where quantization costs (default plan, one conversion per sample; the channels named "
                  "quantized to the board's codes, the others their SI values):", "",
              "| quantized | mean | worst |", "|---|---:|---:|"]
    lines += [f"| {label} | {a['mean']:.3f} | {a['worst']:.3f} |" for label, a in quant.items()]
    return lines


def run(quick: bool) -> str:
    from toolchain import firmware as tool

    build_dir = ROOT / "build" / "bench_aided"
    records = 120 if quick else 400
    prod = tool.build(build_dir, tool.AIDED, kind="production", name="aided_prod")
    prod_sr = tool.build(build_dir, dataclasses.replace(tool.AIDED, mag_sr=True), kind="production", name="aided_prod_sr")
    prod2 = tool.build(build_dir, dataclasses.replace(tool.AIDED, gyro_oversample=2), kind="production",
                       name="aided_prod_x2")
    default = (tool.AIDED.period_ticks, tool.AIDED.acc_every, tool.AIDED.mag_every)
    runs = [(default, 57600, False, 1, False), *((plan, 115200, False, 1, False) for plan in PLANS),
            (default, 115200, True, 1, False), (default, 57600, True, 1, False),
            *((plan, 115200, False, n, mean) for plan, n, mean in OVS_CPU)]
    cpu = {run: cpu_load(tool, build_dir, run[0], run[1], records, *run[2:]) for run in runs}
    prof = profile(tool, build_dir, records)
    dflt = cpu[(default, tool.AIDED.baud, False, 1, False)]
    busy_rec = dflt["busy"] * tool.MACHINE_HZ / dflt["records"]
    acc = broad_accuracy(quick)
    ovs, quant = code_accuracy(tool, quick)
    lines = [
        (f"Default image (`Config(board=\"aided9\")`, `toolchain.firmware.AIDED`): flash **{prod.flash} / "
         f"8192 bytes**, internal RAM **{prod.ram_static} / 256 bytes** static, stack 0x{prod.stack_start:02X}.."
         f"0xFF = {prod.stack_free} bytes; highest SP seen in s51 over the runs below "
         f"0x{max(c['max_sp'] for (_, _, sr, n, _), c in cpu.items() if not sr and n == 1):02X}. With the "
         f"magnetometer's set/reset (`mag_sr=True`): flash {prod_sr.flash}, RAM {prod_sr.ram_static} static, stack "
         f"from 0x{prod_sr.stack_start:02X}, highest SP seen "
         f"0x{max(c['max_sp'] for (_, _, sr, _, _), c in cpu.items() if sr):02X}."),
        "",
        (f"Link v2 settings: a ring of {tool.AIDED.v2_ring} records in the upper RAM, up to "
         f"{tool.AIDED.v2_samples} samples per frame, a DATA frame held back for {tool.AIDED.v2_batch} records "
         f"or {tool.AIDED.v2_hold} ticks ({1000 * tool.AIDED.v2_hold / tool.TICK_HZ:.0f} ms)."),
        "", *_cpu_table(tool, cpu, records)]
    scan = [c["scan"] for (_, _, sr, n, _), c in cpu.items() if not sr and n == 1]
    lines += ["", "A plan whose records/s delivered fall short of those wanted saturates the 8051 (the link "
                  "v2 sender's CPU per byte) or the link: it loses samples, reported in place as OVERRUN, and its "
                  "busy figure is that of a stalled link waiting for acknowledgements, not a feasible load.",
              "", f"A group's scan (3, 6 or 9 conversions + power-down): {min(scan):.0f}..{max(scan):.0f} machine "
                  "cycles on average per plan (one conversion per sample).", "",
              (f"Where the default plan's cycles go (115200 baud; the profile image, -DFW_PROFILE): "
              f"{busy_rec:.0f} busy machine cycles per record (load run); {prof['per_frame']:.1f} records per "
              f"frame; {prof['bytes']:.2f} bytes sent per record at {prof['poll']:.0f} cycles per poll that "
              f"sends one (with the profile's ~40 cycles of timestamps); {prof['rx_bytes']:.2f} ACK bytes "
              f"received per record at {prof['sink']:.0f} cycles per sink call (same); the scan "
              f"{prof['scan']:.0f} cycles per record; the rest is the main loop, the serial interrupt, the "
              "records' encoding and the bench's own idle accounting."), "",
              "Accuracy on BROAD (Laidig, Caruso, Cereatti, Seel, Data 6(7), 2021; the trials in "
              "../shared/data/broad taken at the board's instants, att_ahrs defaults, the accelerometer and "
              "magnetometer in every k-th sample only; total error, RMS per trial, deg; "
              f"{next(iter(acc.values()))['n']} trials):", "",
              "| gyro rate | acc every | mag every | mean | worst |", "|---:|---:|---:|---:|---:|"]
    for (step, (ka, km)), a in acc.items():
        lines.append(f"| {285.714 / step:.1f} Hz | {ka} | {km} | {a['mean']:.2f} | {a['worst']:.2f} |")
    return "\n".join([*lines, "", *_ovs_lines(tool, cpu, ovs, quant, prod2)])
