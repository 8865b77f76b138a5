"""`python -m toolchain.simulate --firmware s51` (`attitude simulate` with the
tooling layer's source): the acquisition side as the real AT89S51 firmware in
s51 (TLC2543 driver, sampling loop and link sender unchanged)."""

from __future__ import annotations

import json

import numpy as np
from conftest import require_tools

from attitude_c.sim import SimConfig, simulate
from attitude_c.sim.sensors import DEG
from toolchain import firmware as tool  # registers the "s51" source
from toolchain.firmware import FirmwareTrajectory
from toolchain.simulate import main

import pytest

pytestmark = pytest.mark.system  # runs the firmware's trajectory through the simulator and s51

# cg-l53 through the default conditioning: 90 °/s ↔ 0.9 · 2048 codes
K = 90.0 * DEG / (0.9 * 2048)


def test_firmware_chain_delivers_every_sample_and_tracks_the_truth() -> None:
    require_tools("sdcc", "s51", "socat", apt="sdcc sdcc-ucsim socat")
    h, dur = 0.08, 4.0
    tr = FirmwareTrajectory(period=h, rad_per_s_per_code=K, duration=dur)
    res = simulate(SimConfig(trajectory=tr, duration=dur, period=h, firmware="s51"))
    s = res.summary["link"]
    n = 50
    # s51 runs in lockstep with the host (an answer at most one step, 43 ms, late:
    # docs/firmware.md); should the firmware skip samples anyway, it reports them in
    # the stream (overrun / gave_up); every sample is accounted for, and the lost ones
    # after the first good sample are held (attitude-rx's policy)
    assert s["delivered"] + s["lost"] == n
    assert s["lost"] == 0 or {"overrun", "gave_up"} & set(s["reports"])
    assert s["max_stack_pointer"] < 0x80
    idx = res.sample_index
    held = set(s["held"])
    assert len(held) <= s["lost"] and set(idx) >= held and list(idx) == sorted(set(idx))
    # the words the firmware sent are the model's codes at the sampling instants
    good = np.array([i not in held for i in idx])
    want = np.array([[int(tool.Gyro(*g).lsb(int(i))) for g in tr.gyros] for i in idx[good]])
    got = np.rint(res.increments[good] / (K * h) + 2047.5).astype(int)
    assert np.max(np.abs(got - want)) <= 1  # the image's sine table: ±1 LSB
    # one midpoint conversion per period of ±25 °/s rates turning at 0.2 Hz: the
    # midpoint rule's (Ωh)²/24 ≈ 4e-4 relative error on ~0.4 rad of motion plus
    # 12-bit quantization keep the error below 2 mrad over 4 s; a held sample j
    # periods after the last good one adds at most |ω̇| j h² (|ω̇| = A Ω: the X/Y
    # rate turns at Ω; the integration starts from the truth at the first good sample)
    amp_w = np.radians(tr.params()["rate_amplitude_xy_dps"]) * 2 * np.pi * tr.params()["frequency_hz"]
    j = [i - max(k for k in idx if k < i and k not in held) for i in sorted(held)]
    bound = 2e-3 + amp_w * h * h * sum(j)
    assert res.summary["errors_rad"]["attitude_angle"]["max_abs"] < bound


def test_firmware_cli_option(tmp_path) -> None:
    require_tools("sdcc", "s51", "socat", apt="sdcc sdcc-ucsim socat")
    out = tmp_path / "fw"
    assert main(["--firmware", "s51", "--duration", "2", "--no-plots",
                 "--no-progress", "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["parameters"]["firmware"] == "s51"
    assert s["parameters"]["trajectory"]["trajectory"] == "firmware"
    assert s["link"]["delivered"] + s["link"]["lost"] == 25
