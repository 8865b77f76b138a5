"""Acquisition sources: what replaces the modeled board (``SimConfig.firmware``).

A source is registered by name (:func:`register_source`) -- the AT89S51
firmware in s51 is one, registered by the tooling layer
(``toolchain/firmware.py``) -- and found by :func:`source`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InvalidArgument
from .conditioning import Conditioning
from .host import AuxStream, Calibration
from .link import Delivered
from .sensors import GyroModel
from .trajectory import Trajectory

if TYPE_CHECKING:  # annotations only: the chain imports this module
    from .chain import Progress, SimConfig

__all__ = ["KNOWN_SOURCES", "Source", "SourceOutput", "register_source", "source"]



@dataclass
class SourceOutput:
    """What an acquisition source hands the host: the ``delivered`` records, the
    ``calibration`` to convert them with, the ``backends`` it ran (for the
    summary) and, when the simulator knows it, the sent stream's record → sample
    map (``stream_sample``; None: the stream's own numbering is the truth)."""

    delivered: Delivered
    calibration: Calibration
    backends: dict[str, Any]
    stream_sample: np.ndarray | None = None
    aux: dict[str, AuxStream] = field(default_factory=dict)


@dataclass(frozen=True)
class Source:
    """An acquisition source that replaces the modeled board (SimConfig.firmware).

    ``acquire(cfg, n, progress)`` delivers the records of n samples;
    ``check(cfg)`` refuses configurations it cannot run (InvalidArgument);
    ``trajectory(cfg_period, gyro, conditioning, duration)`` is the motion the
    source produces (the CLI builds its truth with it); ``description`` says
    what runs."""

    name: str
    description: str
    acquire: Callable[[SimConfig, int, Progress | None], SourceOutput]
    check: Callable[[SimConfig], None]
    trajectory: Callable[[float, GyroModel, Conditioning, float], Trajectory]


_SOURCES: dict[str, Source] = {}

#: Sources this package knows by name but does not contain: where they come from.
KNOWN_SOURCES = {"s51": "the AT89S51 firmware in s51 runs from a source checkout: "
                        "python -m toolchain.simulate --firmware s51 ... (docs/firmware.md)"}


def register_source(src: Source) -> None:
    """Make ``src`` available as ``SimConfig(firmware=src.name)``."""
    _SOURCES[src.name] = src


def source(name: str) -> Source:
    """The registered source ``name`` (InvalidArgument saying where it comes from if absent)."""
    try:
        return _SOURCES[name]
    except KeyError:
        hint = KNOWN_SOURCES.get(name, f"registered: {sorted(_SOURCES) or 'none'}")
        raise InvalidArgument(f"firmware source {name!r} is not available here: {hint}") from None
