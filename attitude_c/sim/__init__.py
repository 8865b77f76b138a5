"""Full-system simulation of the paper's attitude measurement system, as a
pipeline of stages (docs/architecture.md, docs/simulation.md):

    trajectory → sensors → conditioning → ADC → board → link → host → estimator → outputs

one module each (:mod:`.trajectory`, :mod:`.sensors`, :mod:`.conditioning`,
:mod:`.adc`, :mod:`.board`, :mod:`.link`, :mod:`.host`, :mod:`.estimator`,
:mod:`.outputs`); :mod:`.chain` composes them (``simulate``, ``acquire``),
:mod:`.budget` switches the error sources on one at a time, :mod:`.report`
writes a run's plots and files, :mod:`.sweeps` runs many scenarios on Dask
(``sweep``, docs/sweep.md).
"""

from __future__ import annotations

from .adc import AdcModel, quantize_ideal
from .board import Board, BoardStream
from .budget import STAGES, BudgetResult, format_budget, plot_budget, run_budget
from .chain import (
    PAPER_MAXIMA,
    SENSOR_MODES,
    Acquired,
    SimConfig,
    SimResult,
    Source,
    SourceOutput,
    acquire,
    register_source,
    simulate,
    source,
)
from .conditioning import Conditioning
from .estimator import Estimate, Integrate
from .host import Calibration, Decoded, HostDecoder
from .link import Delivered, Link
from .outputs import Errors, attitude_angle, compare, wrap_angle
from .report import format_table, plot_attitude, plot_errors, write_run
from .sensors import GYRO_PRESETS, Gyro, GyroModel, gyro_preset
from .sweeps import load_spec, register_estimator, sweep
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
    "SENSOR_MODES",
    "STAGES",
    "TRAJECTORIES",
    "Acquired",
    "AdcModel",
    "Board",
    "BoardStream",
    "BudgetResult",
    "Calibration",
    "Conditioning",
    "ConingTrajectory",
    "ConstantRateTrajectory",
    "CsvTrajectory",
    "Decoded",
    "Delivered",
    "Errors",
    "Estimate",
    "Gyro",
    "GyroModel",
    "HostDecoder",
    "Integrate",
    "Link",
    "PaperTrajectory",
    "SimConfig",
    "SimResult",
    "Source",
    "SourceOutput",
    "StaticTrajectory",
    "Trajectory",
    "acquire",
    "attitude_angle",
    "compare",
    "euler_rates_to_body",
    "format_budget",
    "format_table",
    "gyro_preset",
    "load_spec",
    "make_trajectory",
    "plot_attitude",
    "plot_budget",
    "plot_errors",
    "quantize_ideal",
    "register_estimator",
    "register_source",
    "run_budget",
    "simulate",
    "source",
    "sweep",
    "wrap_angle",
    "write_run",
]
