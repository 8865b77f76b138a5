"""``attitude ahrs``'s figure: the attitude over time (docs/ahrs.md, "Command").

Panels: yaw, pitch and roll of the estimate (and of the reference when the
recording has one), the three error components of BROAD's metric (with a
reference), the filter's flags (rest, accelerometer gated out, magnetometer
rejected as disturbed) and its gyro-bias estimate; the movement phases of a
BROAD trial shaded in every panel.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from .._io import write_with
from .._plot import panels

FloatArray = NDArray[np.float64]

#: Flags drawn, bottom to top: (ATT_AHRS_F_* name, label).
FLAGS = (("ATT_AHRS_F_REST", "rest"), ("ATT_AHRS_F_ACC_REJECTED", "acc gated out"),
         ("ATT_AHRS_F_MAG_DISTURBED", "mag disturbed"))


@dataclass(frozen=True)
class Trace:
    """What the figure draws; angles in degrees, ``tb`` the times of ``flags`` and ``bias``."""

    t: FloatArray
    euler: FloatArray              #: (N, 3) estimate, yaw pitch roll, °
    ref_euler: FloatArray | None   #: (N, 3) reference, °
    errors: tuple[FloatArray, FloatArray, FloatArray] | None  #: total, heading, inclination, °
    movement: NDArray[np.bool_] | None
    tb: FloatArray
    flags: NDArray[np.int_]        #: ATT_AHRS_F_* bits at ``tb``
    bias: FloatArray               #: (M, 3) °/s at ``tb``
    sequence: str                  #: "zxy" or "zyx"


def _broken(a: FloatArray) -> FloatArray:
    """An angle with NaN where it wraps (±180°), so that the line does not cross the panel."""
    out = np.array(a, dtype=np.float64)
    out[1:][np.abs(np.diff(out)) > 180.0] = np.nan
    return out


def _draw(tr: Trace, path: Path, title: str) -> None:
    from ..names import C

    has_ref = tr.ref_euler is not None
    rows = 6 if tr.errors is not None else 5
    with panels(path, 90, 1.55 * rows, title, legend=has_ref, rows=rows, width=10.0) as axes:
        names = ("yaw", "pitch", "roll")
        for i, ax in enumerate(axes[:3]):
            if tr.ref_euler is not None:
                ax.plot(tr.t, _broken(tr.ref_euler[:, i]), color="0.55", lw=1.6, label="reference")
            ax.plot(tr.t, _broken(tr.euler[:, i]), color="C0", lw=0.8, label="estimate")
            ax.set_ylabel(f"{names[i]} / °")
        axes[0].set_title(f"Euler angles, {'-'.join(tr.sequence)} sequence"
                          + ("; shaded: movement phases (errors scored there)" if tr.movement is not None else ""),
                          fontsize=8.5, loc="left")
        k = 3
        if tr.errors is not None:
            total, heading, incl = tr.errors
            axes[k].plot(tr.t, heading, color="C1", lw=0.7, label="heading")
            axes[k].plot(tr.t, incl, color="C2", lw=0.7, label="inclination")
            axes[k].plot(tr.t, total, color="black", lw=0.6, label="total")
            axes[k].set_ylabel("error / °")
            axes[k].legend(loc="upper right", fontsize=7, ncol=3)
            k += 1
        for j, (name, lab) in enumerate(FLAGS):
            on = (tr.flags & C[name]) != 0
            axes[k].fill_between(tr.tb, j - 0.35, j + 0.35, where=on, step="post", color=f"C{j + 3}", lw=0)
        axes[k].set_yticks(range(len(FLAGS)), [lab for _, lab in FLAGS], fontsize=7)
        axes[k].set_ylim(-0.6, len(FLAGS) - 0.4)
        for i, lab in enumerate(("x (right)", "y (forward)", "z (up)")):
            axes[k + 1].plot(tr.tb, tr.bias[:, i], lw=0.9, label=lab)
        axes[k + 1].set_ylabel("gyro bias / °/s")
        axes[k + 1].legend(loc="upper right", fontsize=7, ncol=3)
        if tr.movement is not None:
            for ax in axes:
                ax.fill_between(tr.t, 0, 1, where=tr.movement, transform=ax.get_xaxis_transform(),
                                color="0.92", lw=0, zorder=0)


def write_plot(path: Path, tr: Trace, title: str) -> None:
    """The figure as PNG to ``path``, complete or not at all."""
    write_with(path, lambda tmp: _draw(tr, tmp, title))
