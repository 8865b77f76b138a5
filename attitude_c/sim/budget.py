"""Error budget: switch the error sources on one at a time, for every method.

Stages (each adds one source to its *base* stage):

1. ``algorithm`` — exact increments, float64: the method's own error;
2. ``+ quantization`` (base 1) — a perfect gyro through conditioning, the
   12-bit ADC and the board's oversampled increment formation, with the
   host's calibration;
3. ``+ gyro noise/bias`` (base 2) — the gyro model's noise, turn-on bias
   (calibrated out up to noise), filter and saturation: the full sensor chain;
4. ``+ float32`` (base 3) — the float32 build of the integrator;
5. ``+ fixed-point`` (base 3) — the Q-format integrator;
6. ``+ link errors`` (base 3) — every sample through the C sender, the
   channel simulator at the budget BER and the C receiver, float64.

The precision and link stages each sit on the full sensor chain rather than
on one another, so that a large link error does not hide the arithmetic's
small one. A source's contribution: for the sensor and link stages the
root-difference-of-squares of the RMS attitude-angle error with and without
it (independent errors add in quadrature; negative when switching it on
lowered the error); for the precision stages, where the same increments give
updates at the same times, directly the RMS angle between the attitudes
computed with and without it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Callable

import numpy as np

from ..core import METHODS, Method
from ..errors import InvalidArgument
from .chain import Acquired, SimConfig, acquire, simulate
from .outputs import attitude_angle

__all__ = ["STAGES", "BudgetResult", "format_budget", "plot_budget", "run_budget"]

STAGES = ("algorithm", "+ quantization", "+ gyro noise/bias", "+ float32", "+ fixed-point",
          "+ link errors")
_BASE = {"+ quantization": "algorithm", "+ gyro noise/bias": "+ quantization",
         "+ float32": "+ gyro noise/bias", "+ fixed-point": "+ gyro noise/bias",
         "+ link errors": "+ gyro noise/bias"}
_DIRECT = ("+ float32", "+ fixed-point")


@dataclass
class BudgetResult:
    methods: list[str]
    stages: list[str]
    rms: np.ndarray  # (stages, methods) RMS attitude-angle error, rad
    max_abs: np.ndarray  # (stages, methods) max attitude-angle error, rad
    contribution: np.ndarray  # (stages, methods) rad
    dominant: dict[str, str]
    link: dict[str, Any]
    params: dict[str, Any]
    skipped: dict[str, str]
    dominant_no_link: dict[str, str]

    def to_dict(self) -> dict[str, Any]:
        return {
            "methods": self.methods, "stages": self.stages,
            "rms_rad": {s: dict(zip(self.methods, self.rms[i].tolist())) for i, s in enumerate(self.stages)},
            "max_abs_rad": {s: dict(zip(self.methods, self.max_abs[i].tolist()))
                            for i, s in enumerate(self.stages)},
            "contribution_rad": {s: dict(zip(self.methods, self.contribution[i].tolist()))
                                 for i, s in enumerate(self.stages)},
            "dominant_source": self.dominant, "dominant_source_without_link": self.dominant_no_link,
            "link": self.link, "parameters": self.params,
            "skipped": self.skipped,
        }


def _stage_configs(base: SimConfig, ber: float) -> list[tuple[str, SimConfig]]:
    full = replace(base, sensors="full", link="none", ber=0.0, precision="f64")
    return [
        ("algorithm", replace(full, sensors="ideal")),
        ("+ quantization", replace(full, sensors="quantized")),
        ("+ gyro noise/bias", full),
        ("+ float32", replace(full, precision="f32")),
        ("+ fixed-point", replace(full, precision="fixed")),
        ("+ link errors", replace(full, link="c", ber=ber)),
    ]


def run_budget(base: SimConfig, methods: tuple[Method, ...] = METHODS, ber: float = 1e-3,
               progress: Callable[[str, int, int], None] | None = None) -> BudgetResult:
    """Run every stage for every method on the scenario of ``base``."""
    stages = _stage_configs(base, ber)
    skipped: dict[str, str] = {}
    names = [s[0] for s in stages]
    cache: dict[tuple[Any, ...], Acquired] = {}
    rms = np.full((len(stages), len(methods)), np.nan)
    mx = np.full_like(rms, np.nan)
    contrib = np.full_like(rms, np.nan)
    q_of: dict[tuple[str, str], np.ndarray] = {}
    link: dict[str, Any] = {}
    total = len(stages) * len(methods)
    done = 0
    for i, (name, cfg) in enumerate(stages):
        key = (cfg.sensors, cfg.link, cfg.ber)
        for j, m in enumerate(methods):
            done += 1
            if progress is not None:
                progress("budget", done, total)
            c = replace(cfg, method=m)
            if key not in cache:
                cache[key] = acquire(c, None)
            try:
                res = simulate(c, None, cache[key])
            except InvalidArgument as exc:  # e.g. no fixed-point rk4
                skipped[f"{name} / {m}"] = str(exc)
                continue
            e = res.summary["errors_rad"]["attitude_angle"]
            rms[i, j] = e["rms"]
            mx[i, j] = e["max_abs"]
            q_of[(name, m)] = res.q_est
            if name == "+ link errors":
                link = res.link_stats
            if name == "algorithm":
                contrib[i, j] = e["rms"]
            elif name in _DIRECT and (_BASE[name], m) in q_of:
                d = attitude_angle(q_of[(_BASE[name], m)], res.q_est)
                contrib[i, j] = float(np.sqrt(np.mean(d * d)))
            else:
                r0 = rms[names.index(_BASE[name]), j]
                dd = e["rms"] ** 2 - r0**2
                contrib[i, j] = float(np.sign(dd) * np.sqrt(abs(dd)))
    dominant: dict[str, str] = {}
    dominant_no_link: dict[str, str] = {}
    for j, m in enumerate(methods):
        col = np.where(np.isnan(contrib[:, j]), -np.inf, contrib[:, j])
        dominant[m] = names[int(np.argmax(col))]
        col_nl = np.where([n == "+ link errors" for n in names], -np.inf, col)
        dominant_no_link[m] = names[int(np.argmax(col_nl))]
    params = base.params()
    params["budget_ber"] = ber
    return BudgetResult(list(methods), names, rms, mx, contrib, dominant, link, params, skipped,
                        dominant_no_link)


def format_budget(b: BudgetResult, markdown: bool = False) -> str:
    """Table: rows = stages, columns = methods; cells = RMS error in rad and in degrees
    (the stage's contribution in rad)."""
    def cell(i: int, j: int) -> str:
        if np.isnan(b.rms[i, j]):
            return "n/a"
        both = f"{b.rms[i, j]:.2e} rad = {np.degrees(b.rms[i, j]):.2e}°"
        if i == 0:
            return both
        return f"{both} ({b.contribution[i, j]:+.1e})"

    head = ["stage"] + b.methods
    rows = [[s] + [cell(i, j) for j in range(len(b.methods))] for i, s in enumerate(b.stages)]
    rows.append(["dominant source"] + [b.dominant[m] for m in b.methods])
    if "+ link errors" in b.stages:
        rows.append(["dominant without link"] + [b.dominant_no_link[m] for m in b.methods])
    if markdown:
        out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        out += ["| " + " | ".join(r) + " |" for r in rows]
    else:
        w = [max(len(r[k]) for r in [head] + rows) for k in range(len(head))]
        out = ["  ".join(h.ljust(w[k]) for k, h in enumerate(head))]
        out += ["  ".join(c.ljust(w[k]) for k, c in enumerate(r)) for r in rows]
    lk = b.link
    if lk:
        out.append(("\n" if markdown else "") +
                   f"link stage (BER {lk.get('ber', 0):g}, seed {lk.get('seed')}): sent {lk.get('sent')}, "
                   f"delivered intact {lk.get('delivered_ok')}, duplicated {lk.get('duplicated')}, "
                   f"corrupted undetected {lk.get('corrupted_undetected')}, lost {lk.get('lost')}")
    for s, why in b.skipped.items():
        out.append(("" if not markdown else "\n") + f"{s}: skipped ({why})")
    return "\n".join(out)


def plot_budget(b: BudgetResult, path: Any, dpi: int = 100) -> None:
    """Grouped bars: each source's contribution (rad, log scale), per method.
    Hatched bars: switching the source on lowered the RMS error."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8.0, 4.4))
    n_s = len(b.stages)
    width = 0.8 / n_s
    x = np.arange(len(b.methods))
    colors = plt.get_cmap("viridis")(np.linspace(0.05, 0.95, n_s))
    negative = []
    for i, s in enumerate(b.stages):
        c = b.contribution[i]
        h = np.where(np.isnan(c), 0.0, np.maximum(np.abs(c), 1e-12))
        bars = ax.bar(x + (i - (n_s - 1) / 2) * width, h, width,
                      label=s if i == 0 else f"{s} (vs {_BASE[s]})" if s in _DIRECT else s,
                      color=colors[i], edgecolor="black", linewidth=0.4)
        negative += [bar for bar, v in zip(bars, c) if v < 0]
    ax.set_yscale("log")
    ax.set_ylim(bottom=1e-9)
    ax.set_xticks(x)
    ax.set_xticklabels(b.methods)
    ax.set_ylabel("contribution to RMS attitude error / rad")
    ax.secondary_yaxis("right", functions=(np.degrees, np.radians)).set_ylabel("/ °")
    p = b.params
    ax.set_title(f"Error budget — {p['trajectory']['trajectory']} trajectory, h = {p['period_s']:g} s, "
                 f"{p['duration_s']:g} s, gyro {p['gyro']['name']}, link BER {p['budget_ber']:g}",
                 fontsize=9)
    ax.axhline(0.12, color="red", linestyle="--", linewidth=0.8)
    ax.text(len(b.methods) - 0.5, 0.12, "paper's max heading error", color="red", fontsize=7,
            ha="right", va="bottom")
    ax.grid(True, axis="y", linestyle=":", linewidth=0.6)
    ax.legend(fontsize=7, ncol=3, loc="upper center", bbox_to_anchor=(0.5, -0.1))
    for bar in negative:  # after the legend, so that its swatches stay plain
        bar.set_hatch("///")
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
