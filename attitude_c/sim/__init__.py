"""Full-system simulation of the paper's attitude measurement system, as a
pipeline of stages (docs/architecture.md, docs/simulation.md):

    trajectory → sensors → conditioning → ADC → board → link → host → estimator → outputs
                 (accelmag: accelerometer, magnetometer    (denoising: between
                  beside the gyro, read by the host)        host and estimator)

one module each (:mod:`.trajectory`, :mod:`.sensors`, :mod:`.accelmag`,
:mod:`.conditioning`, :mod:`.adc`, :mod:`.board`, :mod:`.link`, :mod:`.host`,
:mod:`.denoising`, :mod:`.estimator`, :mod:`.outputs`); :mod:`.chain`
composes them (``simulate``, ``acquire``),
:mod:`.budget` switches the error sources on one at a time, :mod:`.report`
writes a run's plots and files, :mod:`.sweeps` runs many scenarios on Dask
(``sweep``, docs/sweep.md). :mod:`.frontend` models the aided board's analog
accelerometer and magnetometer front ends down to TLC2543 codes (issue 26; not
in the chain yet).
"""

from __future__ import annotations

from .accelmag import (
    ACCEL_PRESETS,
    MAG_PRESETS,
    MagDisturbance,
    SensorErrors,
    VectorSensor,
    VectorSensorModel,
    accel_preset,
    mag_preset,
)
from .adc import ADC_BACKENDS, AdcModel, quantize_ideal
from .board import Board, BoardStream
from .budget import STAGES, BudgetResult, format_budget, plot_budget, run_budget
from .catalog import make_trajectory
from .chain import (
    PAPER_MAXIMA,
    SENSOR_MODES,
    Acquired,
    SimConfig,
    SimResult,
    acquire,
    simulate,
)
from .conditioning import Conditioning
from .denoising import DENOISE_TIMINGS, Denoise
from .estimator import AhrsFilter, Estimate, Integrate
from .host import AuxCalibration, AuxStream, Calibration, Decoded, HostDecoder
from .link import Delivered, Link
from .outputs import Errors, attitude_angle, compare, wrap_angle
from .report import format_table, plot_attitude, plot_errors, write_run
from .sensors import GYRO_PRESETS, Gyro, GyroModel, gyro_preset
from .sources import Source, SourceOutput, register_source, source
from .sweeps import load_spec, register_estimator, sweep
from .trajectory import (
    EARTH,
    TRAJECTORIES,
    ConingTrajectory,
    ConstantRateTrajectory,
    CsvTrajectory,
    Environment,
    LevelTurnTrajectory,
    PaperTrajectory,
    StaticTrajectory,
    Trajectory,
    TurntableTrajectory,
    euler_rates_to_body,
)

__all__ = [
    "ACCEL_PRESETS",
    "ADC_BACKENDS",
    "DENOISE_TIMINGS",
    "EARTH",
    "GYRO_PRESETS",
    "MAG_PRESETS",
    "PAPER_MAXIMA",
    "SENSOR_MODES",
    "STAGES",
    "TRAJECTORIES",
    "Acquired",
    "AdcModel",
    "AhrsFilter",
    "AuxCalibration",
    "AuxStream",
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
    "Denoise",
    "Environment",
    "Errors",
    "Estimate",
    "Gyro",
    "GyroModel",
    "HostDecoder",
    "Integrate",
    "LevelTurnTrajectory",
    "Link",
    "MagDisturbance",
    "PaperTrajectory",
    "SensorErrors",
    "SimConfig",
    "SimResult",
    "Source",
    "SourceOutput",
    "StaticTrajectory",
    "Trajectory",
    "TurntableTrajectory",
    "VectorSensor",
    "VectorSensorModel",
    "accel_preset",
    "acquire",
    "attitude_angle",
    "compare",
    "euler_rates_to_body",
    "format_budget",
    "format_table",
    "gyro_preset",
    "load_spec",
    "mag_preset",
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
