"""Firmware tasks: ``invoke firmware.build`` and ``invoke firmware.sim`` (see docs/firmware.md)."""

from __future__ import annotations

import sys
from pathlib import Path
from types import ModuleType

from invoke import task


def _tool() -> ModuleType:
    from toolchain import firmware  # imported at use: the other tasks need no simulator

    return firmware


@task(help={
    "baud": "UART rate (exact rates of the 11.0592 MHz crystal only: up to 57600 on the AT89S51's Timer 1, "
            "115200 on the aided AT89S52's Timer 2; default 9600, aided 115200)",
    "period_ticks": "sampling period in Timer 0 ticks of 1/3600 s (72 = 20 ms)",
    "max_attempts": "link attempts per block before giving up",
    "out": "output directory (default build/firmware)",
    "link": "link protocol: legacy (AA/BB handshake, default) or v2 (link v2, single-instance sender)",
    "board": "gyro3 (the paper's AT89S51, default) or aided9 (the AT89S52 with accelerometer and "
             "magnetometer: link v2, docs/firmware.md)",
    "acc_every": "aided9: accelerometer record every N samples (0 or a power of two up to 128; default: "
                 "toolchain.firmware.AIDED's, every sample)",
    "mag_every": "aided9: magnetometer record every N samples (likewise)",
    "mag_sr": "aided9: magnetometer set/reset on P3.4, the combined code sent (about 5.5 points of CPU more; "
              "docs/firmware.md)",
    "gyro_oversample": "aided9: gyro conversions summed per sample, 1 (default), 2, 4 or 8 (docs/firmware.md "
                       "\"Gyro oversampling\")",
    "gyro_mean": "aided9, oversampled: send the gyros' rounded mean code instead of the sum (a plain stream)",
})
def build(c, baud=0, period_ticks=72, max_attempts=5, out="", link="legacy", board="gyro3", acc_every=-1,
          mag_every=-1, mag_sr=False, gyro_oversample=1, gyro_mean=False):
    """Build the AT89S51 image with SDCC (4 KB flash, 128 B RAM), or the aided AT89S52 one
    (8 KB, 256 B), and print flash, RAM and free stack."""
    import dataclasses

    tool = _tool()
    if link not in tool.LINKS:
        print(f"--link must be one of {', '.join(tool.LINKS)}, got {link!r}", file=sys.stderr)
        raise SystemExit(2)
    try:
        if board == "aided9":
            cfg = dataclasses.replace(tool.AIDED, baud=int(baud) or tool.AIDED.baud, period_ticks=int(period_ticks),
                                      max_attempts=int(max_attempts),
                                      acc_every=tool.AIDED.acc_every if int(acc_every) < 0 else int(acc_every),
                                      mag_every=tool.AIDED.mag_every if int(mag_every) < 0 else int(mag_every),
                                      mag_sr=bool(mag_sr), gyro_oversample=int(gyro_oversample),
                                      gyro_mean=bool(gyro_mean))
        else:
            cfg = tool.Config(baud=int(baud) or 9600, period_ticks=int(period_ticks), max_attempts=int(max_attempts),
                              link=link, board=board, gyro_oversample=int(gyro_oversample),
                              gyro_mean=bool(gyro_mean))
    except ValueError as exc:
        print(f"invoke firmware.build: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
    name = "attitude_fw_aided" if cfg.aided else "attitude_fw" if link == "legacy" else "attitude_fw_v2"
    try:
        img = tool.build(Path(out) if out else tool.BUILD, cfg, kind="production", name=name)
    except tool.FirmwareTooBig as exc:
        print(f"firmware does not fit: {exc}", file=sys.stderr)
        raise SystemExit(1) from None
    print(img.size_report())
    print(f"image: {img.ihx}")


@task(help={
    "samples": "samples to receive (the firmware stops after them)",
    "baud": "UART rate",
    "period_ticks": "sampling period in ticks of 1/3600 s (108 = 30 ms: no overruns against a host on a pty)",
    "fault": "ADC model fault: dout_stuck_high, dout_stuck_low, eoc_stuck or adc_error_at=K (one failed scan)",
    "timeout": "wall-clock limit in seconds",
    "impl": "host receiver: c (libattitude through CFFI) or python (attitude_c.link)",
})
def sim(c, samples=20, baud=9600, period_ticks=108, fault="", timeout=120, impl="c"):
    """Run the firmware in s51 -t C51 against the C receiver on a socat pty pair; print the samples received."""
    tool = _tool()
    cfg = tool.Config(baud=int(baud), period_ticks=int(period_ticks), selftest_retry=360)
    # stop after the samples; a failing self-test never samples: stop after BOOT and two SELFTEST reports
    stop = ({"sim_samples": int(samples)} if not fault or fault.startswith("adc_error_at")
            else {"sim_blocks": 3})
    img = tool.build(tool.BUILD, cfg, kind="sim", faults=[fault] if fault else [], **stop)
    print(img.size_report())
    res = tool.run(img, tool.LinkHost(impl), timeout=float(timeout))
    print(f"# {res.sim_seconds:.3f} s simulated in {res.wall_seconds:.1f} s; max SP 0x{res.max_sp:02X}")
    print("# seq    X     Y     Z   (12-bit codes; model input in LSB in brackets)")
    for x in res.stream:
        if isinstance(x, tool.Sample):
            exp = " ".join(f"{g.lsb(x.seq):7.1f}" for g in tool.GYROS)
            print(f"{x.seq:5d} {x.codes[0]:5d} {x.codes[1]:5d} {x.codes[2]:5d}   [{exp}]")
        else:
            print(f"# report {x.kind}: {x.raw.hex()}")
    print(f"# firmware: {res.stats}")
    print(f"# receiver: {res.host.stats()}")
