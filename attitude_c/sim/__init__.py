"""Full-system simulation of the paper's attitude measurement system.

trajectory → gyros → analog conditioning → TLC2543 ADC (C driver + device
model) → acquisition-board increment formation → serial link (C sender and
receiver, optional channel errors) → integrator (any method, f64/f32/fixed)
→ attitude → errors against the truth. See docs/simulation.md.
"""

from __future__ import annotations

from .budget import STAGES, BudgetResult, format_budget, plot_budget, run_budget
from .chain import PAPER_MAXIMA, Acquired, SimConfig, SimResult, acquire, simulate
from .report import format_table, plot_attitude, plot_errors, write_run
from .sensors import (
    GYRO_PRESETS,
    AdcModel,
    Board,
    Calibration,
    Conditioning,
    GyroModel,
    gyro_preset,
)
from .trajectory import (
    TRAJECTORIES,
    ConingTrajectory,
    ConstantRateTrajectory,
    CsvTrajectory,
    PaperTrajectory,
    StaticTrajectory,
    Trajectory,
    euler_rates_to_body,
    make_trajectory,
)

__all__ = [
    "GYRO_PRESETS",
    "PAPER_MAXIMA",
    "STAGES",
    "TRAJECTORIES",
    "Acquired",
    "AdcModel",
    "Board",
    "BudgetResult",
    "Calibration",
    "Conditioning",
    "ConingTrajectory",
    "ConstantRateTrajectory",
    "CsvTrajectory",
    "GyroModel",
    "PaperTrajectory",
    "SimConfig",
    "SimResult",
    "StaticTrajectory",
    "Trajectory",
    "acquire",
    "euler_rates_to_body",
    "format_budget",
    "format_table",
    "gyro_preset",
    "make_trajectory",
    "plot_attitude",
    "plot_budget",
    "plot_errors",
    "run_budget",
    "simulate",
    "write_run",
]
