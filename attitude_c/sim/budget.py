"""Error budget: switch the error sources on one at a time, for every method.

Stages (cumulative, each adds one source to the previous):

1. ``algorithm`` — exact increments, float64: the method's own error;
2. ``+ quantization`` — a perfect gyro through conditioning, the 12-bit ADC
   and the board's oversampled increment formation, with calibration;
3. ``+ gyro noise/bias`` — the gyro model's noise, turn-on bias (calibrated
   out up to noise), filter and saturation;
4. ``+ link errors`` — every sample through the C link at the budget BER;
5. ``+ float32`` — the float32 build of the integrator;
6. ``+ fixed-point`` — the Q-format integrator instead of float32 (when the
   installed core has it).

A source's contribution is the root-difference-of-squares of the RMS
attitude-angle error before and after it is switched on (errors of
independent sources add in quadrature), signed when switching it on
lowered the error.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Callable

import numpy as np

from . import _integ
from .chain import Acquired, SimConfig, acquire, simulate

__all__ = ["STAGES", "BudgetResult", "format_budget", "plot_budget", "run_budget"]

STAGES = ("algorithm", "+ quantization", "+ gyro noise/bias", "+ link errors", "+ float32",
          "+ fixed-point")


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

    def to_dict(self) -> dict[str, Any]:
        return {
            "methods": self.methods, "stages": self.stages,
            "rms_rad": {s: dict(zip(self.methods, self.rms[i].tolist())) for i, s in enumerate(self.stages)},
            "max_abs_rad": {s: dict(zip(self.methods, self.max_abs[i].tolist()))
                            for i, s in enumerate(self.stages)},
            "contribution_rad": {s: dict(zip(self.methods, self.contribution[i].tolist()))
                                 for i, s in enumerate(self.stages)},
            "dominant_source": self.dominant, "link": self.link, "parameters": self.params,
            "skipped": self.skipped,
        }


def _stage_configs(base: SimConfig, ber: float) -> list[tuple[str, SimConfig]]:
    out = [
        ("algorithm", replace(base, sensors="ideal", link="none", ber=0.0, precision="f64")),
        ("+ quantization", replace(base, sensors="quantized", link="none", ber=0.0, precision="f64")),
        ("+ gyro noise/bias", replace(base, sensors="full", link="none", ber=0.0, precision="f64")),
        ("+ link errors", replace(base, sensors="full", link="c", ber=ber, precision="f64")),
        ("+ float32", replace(base, sensors="full", link="c", ber=ber, precision="f32")),
        ("+ fixed-point", replace(base, sensors="full", link="c", ber=ber, precision="fixed")),
    ]
    return out


def run_budget(base: SimConfig, methods: tuple[str, ...] = _integ.METHODS, ber: float = 1e-3,
               progress: Callable[[str, int, int], None] | None = None) -> BudgetResult:
    """Run every stage for every method on the scenario of ``base``."""
    stages = _stage_configs(base, ber)
    skipped: dict[str, str] = {}
    try:
        from .. import link as _link  # noqa: F401
    except ImportError:
        skipped["+ link errors"] = "attitude_c.link is not built: later stages use no link"
        stages = [(n, replace(c, link="none", ber=0.0) if c.link == "c" else c)
                  for n, c in stages if n != "+ link errors"]
    if not _integ.precision_available("fixed"):
        skipped["+ fixed-point"] = "precision='fixed' is not available in the installed core"
        stages = [s for s in stages if s[0] != "+ fixed-point"]
    cache: dict[tuple[Any, ...], Acquired] = {}
    rms = np.zeros((len(stages), len(methods)))
    mx = np.zeros_like(rms)
    link: dict[str, Any] = {}
    total = len(stages) * len(methods)
    done = 0
    for i, (name, cfg) in enumerate(stages):
        key = (cfg.sensors, cfg.link, cfg.ber)
        for j, m in enumerate(methods):
            c = replace(cfg, method=m)
            if key not in cache:
                cache[key] = acquire(c, None)
            res = simulate(c, None, cache[key])
            e = res.summary["errors_rad"]["attitude_angle"]
            rms[i, j] = e["rms"]
            mx[i, j] = e["max_abs"]
            if name == "+ link errors":
                link = res.link_stats
            done += 1
            if progress is not None:
                progress("budget", done, total)
    contrib = np.zeros_like(rms)
    contrib[0] = rms[0]
    d = rms[1:] ** 2 - rms[:-1] ** 2
    contrib[1:] = np.sign(d) * np.sqrt(np.abs(d))
    dominant = {m: stages[int(np.argmax(contrib[:, j]))][0] for j, m in enumerate(methods)}
    params = base.params()
    params["budget_ber"] = ber
    return BudgetResult(list(methods), [s[0] for s in stages], rms, mx, contrib, dominant, link,
                        params, skipped)


def format_budget(b: BudgetResult, markdown: bool = False) -> str:
    """Table: rows = stages, columns = methods; cells = RMS error (contribution)."""
    def cell(i: int, j: int) -> str:
        if i == 0:
            return f"{b.rms[i, j]:.2e}"
        return f"{b.rms[i, j]:.2e} ({b.contribution[i, j]:+.1e})"

    head = ["stage"] + b.methods
    rows = [[s] + [cell(i, j) for j in range(len(b.methods))] for i, s in enumerate(b.stages)]
    rows.append(["dominant source"] + [b.dominant[m] for m in b.methods])
    if markdown:
        out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        out += ["| " + " | ".join(r) + " |" for r in rows]
    else:
        w = [max(len(r[k]) for r in [head] + rows) for k in range(len(head))]
        out = ["  ".join(h.ljust(w[k]) for k, h in enumerate(head))]
        out += ["  ".join(c.ljust(w[k]) for k, c in enumerate(r)) for r in rows]
    for s, why in b.skipped.items():
        out.append(("" if not markdown else "\n") + f"{s}: skipped ({why})")
    return "\n".join(out)


def plot_budget(b: BudgetResult, path: Any, dpi: int = 100) -> None:
    """Grouped bars: RMS attitude error after each stage, per method (log scale)."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8.0, 4.2))
    n_s = len(b.stages)
    width = 0.8 / n_s
    x = np.arange(len(b.methods))
    greys = plt.get_cmap("viridis")(np.linspace(0.05, 0.95, n_s))
    for i, s in enumerate(b.stages):
        ax.bar(x + (i - (n_s - 1) / 2) * width, np.maximum(b.rms[i], 1e-12), width, label=s,
               color=greys[i], edgecolor="black", linewidth=0.4)
    ax.set_yscale("log")
    ax.set_xticks(x)
    ax.set_xticklabels(b.methods)
    ax.set_ylabel("RMS attitude error / rad")
    p = b.params
    ax.set_title(f"Error budget — {p['trajectory']['trajectory']} trajectory, h = {p['period_s']:g} s, "
                 f"{p['duration_s']:g} s, gyro {p['gyro']['name']}, BER {p['budget_ber']:g}", fontsize=9)
    ax.axhline(0.12, color="red", linestyle="--", linewidth=0.8)
    ax.text(len(b.methods) - 0.5, 0.12, "paper's max heading error", color="red", fontsize=7,
            ha="right", va="bottom")
    ax.grid(True, axis="y", linestyle=":", linewidth=0.6)
    ax.legend(fontsize=7, ncol=3, loc="upper center", bbox_to_anchor=(0.5, -0.1))
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


