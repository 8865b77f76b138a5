"""Figure helpers shared by the result writers (``attitude simulate``'s and
``attitude ahrs``'s plots): matplotlib without a display, and the stacked
panels over t every figure of the project uses."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path
from typing import Any


def plt() -> Any:
    """matplotlib.pyplot on the Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as pyplot

    return pyplot


@contextlib.contextmanager
def panels(path: Path, dpi: int, height: float, title: str, legend: bool = True, rows: int = 3,
           width: float = 7.0) -> Iterator[Any]:
    """``rows`` stacked panels over t (the block draws into the axes it gets), then
    the frame every figure shares: dotted grid, legend in the first panel, t
    axis, ``title``; saved as PNG to ``path`` as it is (the caller makes the
    write atomic) and closed."""
    pyplot = plt()
    fig, axes = pyplot.subplots(rows, 1, figsize=(width, height), sharex=True)
    try:
        yield axes
        for ax in axes:
            ax.grid(True, linestyle=":", linewidth=0.6)
        if legend:
            axes[0].legend(loc="upper right", fontsize=8)
        axes[-1].set_xlabel("t / s")
        fig.suptitle(title, fontsize=9.5)
        fig.tight_layout()
        fig.savefig(path, dpi=dpi, format="png")
    finally:
        pyplot.close(fig)
