"""The simulator as a source of the display: a thin adapter over
:mod:`attitude_c.sim`'s public API (``SimConfig``, ``simulate``) and the
simulator's option table (:mod:`attitude_c.sim.options`), so that
``attitude view --simulate [SIMULATE OPTIONS]`` takes exactly the options
``attitude simulate`` takes for a run.

Everything the view knows of the simulator is in this module: when the
simulator becomes a pipeline of stages, only this file follows. Today the
whole run is simulated first (in the source's thread; the page shows the
progress), then played at ``speed`` times real time: one display sample per
attitude update, with the simulator's truth beside the estimate and the
body rate of the update's last gyro sample (its increment over the period).
A run with a GNSS receiver (``--gnss PRESET``) carries its fixes as attitude-rx
does: the newest fix delivered, on the first sample after its delivery.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Iterator, Mapping, Sequence
from typing import Any

import numpy as np

from ..errors import InvalidArgument
from ..sim.gnss_model import FIX_DTYPE
from ..sim.options import add_arguments, from_namespace
from .sources import Item, Source, _filter_counters, gnss_fix_names, pace
from .stream import Hub, row

__all__ = ["SimulatorSource", "gnss_object", "parse_simulate_options"]

#: attitude simulate's options that write files or run a budget: not what a display does.
_NOT_HERE = ("--budget", "--methods", "--budget-ber", "--out", "--no-plots", "--json")


def _simulate_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="attitude view --simulate",
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    add_arguments(p)
    p.add_argument("--no-progress", action="store_true", help="(attitude simulate's; the page shows the progress)")
    return p


def parse_simulate_options(argv: Sequence[str], ahrs_settings: Mapping[str, Any] | None = None) -> Any:
    """``attitude simulate`` options -> the simulator's configuration
    (``SimConfig``); ``ahrs_settings`` (``attitude view --ahrs-setting``) come
    before those of ``--ahrs-setting`` in ``argv``. A bad option exits with the usage message (status 2);
    one that makes no sense for a display raises InvalidArgument, options
    that do not go together ValueError."""
    from ..sim import SimConfig
    from ..sim.configure import build

    given = [f for f in _NOT_HERE if any(a == f or a.startswith(f + "=") for a in argv)]
    if given:
        raise InvalidArgument(f"{', '.join(given)}: not for the display (attitude simulate writes files and budgets)")
    args = _simulate_parser().parse_args(list(argv))
    if ahrs_settings:
        args.ahrs_setting = [*ahrs_settings.items(), *(args.ahrs_setting or ())]
    return SimConfig(**build(from_namespace(args)))


class SimulatorSource(Source):
    """``simulate(cfg)`` once, then its attitude updates played at ``speed``."""

    def __init__(self, cfg: Any, speed: float = 1.0) -> None:
        super().__init__()
        if not (math.isfinite(speed) and speed > 0):
            raise InvalidArgument(f"speed must be a finite number > 0, got {speed!r}")
        cfg.validate()
        self.cfg = cfg
        self.speed = speed
        self.result: Any = None
        self.description = (f"simulator: {cfg.trajectory.name} trajectory, {cfg.duration:g} s, period "
                            f"{cfg.period:g} s, {cfg.method if cfg.estimator == 'integrator' else cfg.estimator} "
                            f"({cfg.precision}), sensors {cfg.sensors}, "
                            f"link {cfg.link}"
                            + (f", board {cfg.board_kind}" if cfg.board_kind != "gyro3" else "")
                            + f", at {speed:g}x")

    def run(self, hub: Hub) -> None:
        from ..sim import simulate

        hub.status("starting", "simulating...")

        def progress(stage: str, done: int, total: int) -> None:
            hub.status("starting", f"simulating: {stage} {100.0 * done / max(total, 1):.0f} %")

        t0 = time.monotonic()
        res = simulate(self.cfg, progress=progress)
        self.result = res
        self.set_counts(_link_counters(res.link_stats))
        t_first = float(res.t[0]) if len(res.t) else 0.0
        hub.event(t_first, "note", {"note": f"simulated {self.cfg.duration:g} s in {time.monotonic() - t0:.1f} s: "
                                            f"{len(res.t)} attitude updates"})
        hub.status("running", f"playing the simulation at {self.speed:g}x")
        n = pace(hub, self.items(res), self.speed, self._stop, on_counters=self.set_counts)
        if not self._stop.is_set():
            hub.status("ended", f"simulation finished ({n} attitude updates, {self.cfg.duration:g} s)")

    def items(self, res: Any) -> Iterator[Item]:
        """One sample per attitude update: estimate, truth, the newest gyro sample's rate."""
        h = self.cfg.period
        t0 = self.cfg.trajectory.t_start
        # an update at t = t0 + (n + offset) h, offset 1 (end of the sample) or 0.5 (rk4)
        ns = np.round((res.t - t0) / h - 0.75).astype(np.int64)
        j = np.clip(np.searchsorted(res.sample_index, ns), 0, max(len(res.sample_index) - 1, 0))
        rates = res.increments[j] / h if len(res.increments) else np.full((len(ns), 3), np.nan)
        bias_t = res.bias_t if res.bias_t is not None else np.zeros(0)
        fixes = self.cfg.gnss.fixes(self.cfg.trajectory, self.cfg.duration, self.cfg.seed) \
            if self.cfg.gnss is not None else np.zeros(0, dtype=FIX_DTYPE)
        b = f = 0
        for k in range(len(res.t)):
            t = float(res.t[k])
            while b < len(bias_t) and bias_t[b] <= t:  # the filter's gyro-bias estimate, as attitude-rx's
                yield (float(bias_t[b]), "counters", _filter_counters(np.degrees(res.bias[b]).tolist(), None))
                b += 1
            yield (t, "sample", row(t, res.q_est[k], n=int(ns[k]), rate=rates[k], q_true=res.q_true[k],
                                    euler=res.euler_est[k]))
            if f < len(fixes) and fixes["t_delivered"][f] <= t:  # as attitude-rx: the newest fix delivered,
                while f + 1 < len(fixes) and fixes["t_delivered"][f + 1] <= t:  # on the first line after it
                    f += 1
                yield (t, "gnss", gnss_object(fixes[f], t))
                f += 1


def gnss_object(fix: Any, t: float) -> dict[str, Any]:
    """One simulated fix (a :data:`FIX_DTYPE` row) as attitude-rx's ``"gnss"`` object on a line at
    time ``t`` (``age_s``: t minus the fix's time of measurement; ``source`` "sim")."""
    def real(x: Any) -> float | None:
        return float(x) if math.isfinite(x) else None

    ftype = int(fix["fix_type"])  # FIX_DTYPE's codes are NAV-PVT's, as att_gnss_fix_type
    up = real(-fix["vd"]) if ftype == 3 else None  # a 2-D fix reports vd = 0: not a measurement
    return {"fix": gnss_fix_names()[ftype], "valid": ftype in (2, 3), "speed": real(fix["speed"]),
            "track_deg": real(fix["track"]), "vel_enu": [real(fix["ve"]), real(fix["vn"]), up],
            "sats": int(fix["nsat"]), "pdop": real(fix["pdop"]), "age_s": max(0.0, t - float(fix["t_measured"])),
            "source": "sim"}


def _link_counters(stats: dict[str, Any]) -> dict[str, Any]:
    """The simulated link's totals for the whole run (flattened)."""
    out: dict[str, Any] = {}
    snd = stats.get("sender", {}) if isinstance(stats.get("sender"), dict) else {}
    rcv = stats.get("receiver", {}) if isinstance(stats.get("receiver"), dict) else {}
    if rcv:
        out["blocks"] = rcv.get("blocks_accepted", 0)
        out["naks"] = rcv.get("naks", 0)
        out["timeouts"] = snd.get("timeouts", rcv.get("timeouts", 0))
    for k in ("duplicated", "lost", "gave_up", "corrupted_undetected", "sent", "delivered"):
        if isinstance(stats.get(k), (int, float)):
            out["duplicates" if k == "duplicated" else k] = stats[k]
    out["link"] = str(stats.get("link", ""))
    out["note"] = "link counters: totals of the whole simulated run"
    return out
