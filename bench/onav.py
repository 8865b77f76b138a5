"""Issue 30 on a public car log: the HGuide n380 drives of the PyPI package ``onavdata``
0.2.5 (read by ``attitude_c.onav``; docs/gnss.md, "Public recordings with GNSS"), with this
filter GNSS-aided and not, VQF and Fusion.

The data is not shipped with the project (its licence is not stated): give onavdata's
``data`` folder with ``--data`` (``pip download --no-deps onavdata==0.2.5``, unzip the wheel:
``onavdata/data``), or have the package installed. Without it a plain ``invoke bench`` skips
this benchmark with a message; ``--only onav`` fails with that message.

Filters, as in ``bench/gnss_accept.py``: this filter (``attitude_c.ahrs``, default settings,
six-axis: the n380 has no magnetometer) with each GNSS velocity (ENU, up measured, 1σ the
larger of the receiver's east and north sigmas) given at its time of validity (the files
give no latency), and without; VQF (``bench/broad.py``'s configuration, its 6-D output) and
Fusion (``bench/broad.py``'s settings, a zero magnetometer, which Fusion ignores). The time
step of each sample is the interval of the IMU's time stamps (one gap of 0.02 s). Every
filter aligns itself on the first samples (no filter is given the reference).

Figures: roll and pitch (z-x-y Euler, docs/conventions.md) errors against the n380's own
INS attitude, RMS and max over the samples from ``CONVERGE_S`` after the first one to the
end where the INS is in navigation mode, and the share of those samples with roll or pitch
beyond issue 30's ``LIMIT_DEG``. Heading is not judged: no filter here has a
heading reference (no magnetometer; velocity aiding does not observe heading in this
filter), so each holds the heading it started with. The reference is the n380's INS on the
same IMU: it agrees with gravity at standstill to about 0.3° (median; ``python -m
attitude_c.onav``), which is the floor of any figure here.

    invoke bench --only onav --data DIR     # DIR: onavdata's data folder
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

TITLE = "GNSS-velocity aiding on a public car log (onavdata's HGuide n380 drives; issue 30)"
RECORDINGS = ("n380-hill", "n380-stoplights")  #: keys of attitude_c.onav.RECORDINGS
LIMIT_DEG = 0.5  #: issue 30: roll and pitch error with GNSS aiding ≤ 0.5°
CONVERGE_S = 60.0  #: s from the first sample before the errors are judged (every filter's alignment)
FILTERS = ("aided", "unaided", "VQF", "Fusion")
LABELS = {"aided": "this filter, GNSS-aided", "unaided": "this filter, no GNSS", "VQF": "VQF", "Fusion": "Fusion"}
HOW = ("no onavdata data folder: `pip download --no-deps onavdata==0.2.5`, unzip the wheel and give "
       "its onavdata/data folder with --data (or pip install --no-deps onavdata==0.2.5)")


def data_dir(data: str | None) -> Path | None:
    """onavdata's ``data`` folder: ``data`` if it holds the n380 drives, else the installed
    package's; None when neither (the runner then skips this benchmark, saying :data:`HOW`)."""
    from attitude_c import onav

    base = Path(data) if data else onav.default_dir()
    if base is None:
        return None
    return base if all((base / onav.RECORDINGS[r][1]).is_dir() for r in RECORDINGS) else None


def missing(data: str | None = None) -> str | None:
    """Why this benchmark cannot run (the runner's skip message), or None."""
    return None if data_dir(data) is not None else HOW


def tilt_errors(q: np.ndarray, q_ref: np.ndarray) -> np.ndarray:
    """(n, 2) roll and pitch errors (rad, wrapped to ±π) of ``q`` against ``q_ref`` (z-x-y
    Euler; a heading difference does not enter them)."""
    from attitude_c.core import quat_to_euler

    d = quat_to_euler(q)[:, [2, 1]] - quat_to_euler(q_ref)[:, [2, 1]]
    return (d + np.pi) % (2 * np.pi) - np.pi


def figures(err: np.ndarray) -> tuple[float, float, float, float, float]:
    """Roll RMS, roll max, pitch RMS, pitch max (°) of errors (n, 2) in rad, and the share of
    samples with roll or pitch beyond LIMIT_DEG."""
    e = np.degrees(err)
    rms, mx = np.sqrt(np.mean(e ** 2, axis=0)), np.max(np.abs(e), axis=0)
    beyond = float(np.mean(np.max(np.abs(e), axis=1) > LIMIT_DEG))
    return float(rms[0]), float(mx[0]), float(rms[1]), float(mx[1]), beyond


class _Peer:
    """The attributes bench/broad.py's peers read."""

    def __init__(self, rec: Any) -> None:
        self.rate, self.gyr, self.acc = rec.rate, rec.gyr, rec.acc
        self.n = len(rec.t)
        self.mag = np.zeros_like(rec.acc)  # none: Fusion skips a zero magnetometer


def run_filters(rec: Any) -> dict[str, np.ndarray]:
    """Every filter's attitudes (n, 4) over the recording ``rec`` (module doc)."""
    from attitude_c import ahrs
    from bench.broad import run_fusion, run_vqf_batch

    dt = np.diff(rec.t, prepend=rec.t[0] - 1.0 / rec.rate)
    clock = rec.gnss_t - rec.t[0] + dt[0]  # the filter's clock: sample k at the sum of k + 1 steps
    sigma = np.max(rec.gnss_sigma[:, :2], axis=1)
    p = _Peer(rec)
    return {"aided": ahrs(rec.gyr, rec.acc, dt=dt, gnss_t=clock, gnss_vel=rec.gnss_vel, gnss_sigma=sigma),
            "unaided": ahrs(rec.gyr, rec.acc, dt=dt),
            "VQF": np.asarray(run_vqf_batch(p)["quat6D"], dtype=float),
            "Fusion": np.asarray(run_fusion(p), dtype=float)}


def evaluate(rec: Any) -> dict[str, tuple[float, float, float, float, float]]:
    """Each filter's figures on ``rec`` (module doc)."""
    judged = (rec.t >= rec.t[0] + CONVERGE_S) & np.isfinite(rec.q_ref).all(axis=1)
    return {k: figures(tilt_errors(q[judged], rec.q_ref[judged])) for k, q in run_filters(rec).items()}


def run(quick: bool = False, data: str | None = None) -> str:
    from attitude_c import onav

    base = data_dir(data)
    if base is None:
        raise RuntimeError(HOW)
    names = RECORDINGS[:1] if quick else RECORDINGS
    head = ["recording", "reference 1σ roll / pitch (°)"] + [f"{LABELS[k]}: {ax}" for k in FILTERS for ax in ("roll", "pitch")]
    lines = [
        ("Recordings: onavdata 0.2.5's HGuide n380 drives (`attitude_c.onav`; docs/gnss.md, \"Public recordings "
         "with GNSS\"); their data is not shipped with the project. Filters and figures: `bench/onav.py`. Cells: "
         f"RMS / max of the roll or pitch error (°) against the n380's own INS attitude, from {CONVERGE_S:g} s "
         "after the first sample to the end, where the INS is in navigation mode. That reference is on the same "
         "IMU and agrees with gravity at standstill only to about 0.3° (median; `python -m attitude_c.onav`): "
         "figures near it are the data's floor. Heading is not judged (no magnetometer: module doc)."),
        "",
        "| " + " | ".join(head) + " |",
        "|---|---|" + "---:|" * (2 * len(FILTERS)),
    ]
    beyond = ["| recording | " + " | ".join(LABELS[k] for k in FILTERS) + " |", "|---|" + "---:|" * len(FILTERS)]
    for name in names:
        rec = onav.load(name, base)
        f = evaluate(rec)
        assert rec.ref_sigma is not None  # the n380's reference states its 1σ
        s = np.degrees(np.nanmedian(rec.ref_sigma[:, :2], axis=0))
        cells = [f"{f[k][i]:.2f} / {f[k][i + 1]:.2f}" for k in FILTERS for i in (0, 2)]
        lines.append(f"| {name} | {s[0]:.3f} / {s[1]:.3f} | " + " | ".join(cells) + " |")
        beyond.append(f"| {name} | " + " | ".join(f"{f[k][4]:.1%}" for k in FILTERS) + " |")
    note = f"Share of the judged samples with roll or pitch error beyond {LIMIT_DEG:g}° (issue 30's target with aiding):"
    return "\n".join([*lines, "", note, "", *beyond]) + "\n"


if __name__ == "__main__":  # python -m bench.onav DATA_DIR
    import sys

    print(run(data=sys.argv[1] if len(sys.argv) > 1 else None))
