"""``attitude calibrate`` on a simulated aided board, against the truth.

Simulates the analog front ends (attitude_c.sim.frontend: the adxl335 and
hmc1043-ad623 presets with their errors drawn from the seed, a hard and a soft
iron) held still in ``--positions`` positions (the six faces, then random
tilts) and turned through random directions; writes the recording as the
CSV ``attitude calibrate`` reads, runs the command, converts the recording
with the written config through the library's C converter and prints how far
the result is from the truth (docs/sensor.md, "Calibration").

    PYTHONPATH=. python3 examples/calibrate_simulated.py --seed 0 --out /tmp/cal
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Literal

import numpy as np

from attitude_c.cli import main as attitude
from attitude_c.sensorcal import SensorConfig, pose_means
from attitude_c.sim.accelmag import G0
from attitude_c.sim.frontend import ACCEL_FRONTENDS, MAG_FRONTENDS, flip_code, tlc2543_codes

ACC, MAG = ACCEL_FRONTENDS["adxl335"], MAG_FRONTENDS["hmc1043-ad623"]
FIELD_UT = 50.6  # the simulator's default site (attitude_c.sim.trajectory.EARTH)
HARD_UT = np.array([14.0, -9.0, 6.0])
SOFT = np.array([[1.06, 0.04, -0.02], [0.04, 0.95, 0.03], [-0.02, 0.03, 1.01]])


def _directions(rng: np.random.Generator, k: int) -> np.ndarray:
    d = rng.normal(size=(k, 3))
    return d / np.linalg.norm(d, axis=1)[:, None]


def _read_config(path: Path, prefix: Literal["acc", "mag"]) -> SensorConfig:
    keys = dict(line.split(" = ", 1) for line in path.read_text().splitlines() if line.startswith(prefix + "-"))
    vals = {k.split("-", 1)[1]: v for k, v in keys.items()}
    num = {k: np.array([float(x) for x in v.split(",")]) for k, v in vals.items() if k != "axes"}
    return SensorConfig(prefix, num["zero"], num["scale"], vals["axes"], num["matrix"].reshape(3, 3), num["bias"])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--positions", type=int, default=30)
    ap.add_argument("--rows", type=int, default=200, help="samples per position, 10 ms apart")
    ap.add_argument("--out", type=Path, default=Path("results/calibrate-simulated"))
    a = ap.parse_args()
    rng = np.random.default_rng(a.seed)
    a.out.mkdir(parents=True, exist_ok=True)
    d = np.vstack([np.eye(3), -np.eye(3), _directions(rng, max(0, a.positions - 6))])[:a.positions] * G0
    f = np.repeat(d, a.rows, axis=0)
    pose = np.repeat(np.arange(len(d)), a.rows)
    acc_err, mag_err = ACC.draw_errors(rng), MAG.draw_errors(rng)
    acc = tlc2543_codes(ACC.volts(f, acc_err, 0.01, rng), ACC.supply_v)
    m = _directions(rng, len(f)) * FIELD_UT
    mag = flip_code(*MAG.set_reset_codes(m @ SOFT.T + HARD_UT, mag_err, 0.01, rng))
    rec = a.out / "recording.csv"
    np.savetxt(rec, np.column_stack([pose, acc, mag]), fmt="%d", delimiter=",", comments="",
               header="pose,acc_x,acc_y,acc_z,mag_x,mag_y,mag_z")
    conf = a.out / "rx.conf"
    rc = attitude(["calibrate", "--acc", str(rec), "--mag", str(rec), "--out", str(conf),
                   "--mag-field", str(FIELD_UT)])
    if rc != 0:
        return rc
    out_a = pose_means(_read_config(conf, "acc").convert(acc), pose)[0]
    nominal = SensorConfig("acc", np.full(3, 2048.0), np.full(3, ACC.units_per_code))
    raw_a = pose_means(nominal.convert(acc), pose)[0]
    out_m = _read_config(conf, "mag").convert(mag)
    cross = np.abs(acc_err.misalignment - np.eye(3)).max()
    print(f"truth: zero-g errors {np.round(acc_err.bias * 4096, 1).tolist()} codes, sensitivity errors "
          f"{np.round(acc_err.scale * 100, 2).tolist()} %, cross-axis up to {cross:.4f}")

    def mg(v: np.ndarray) -> float:
        return float(np.abs(np.linalg.norm(v, axis=1) - G0).max() / G0 * 1e3)

    print(f"accelerometer: |a| - g over the positions: max {mg(out_a):.3f} mg "
          f"(nominal zero and scale: max {mg(raw_a):.1f} mg)")
    rms = np.sqrt(np.mean((np.linalg.norm(out_m, axis=1) - FIELD_UT) ** 2))
    print(f"magnetometer: |m| - F RMS {rms:.3f} uT (hard iron {HARD_UT.tolist()} uT, soft iron up to "
          f"{np.abs(SOFT - np.eye(3)).max():.2f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
