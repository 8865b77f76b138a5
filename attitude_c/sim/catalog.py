"""Every trajectory of the simulator by name: the motions of :mod:`.trajectory` and the
vehicles of :mod:`.vehicle` (which build on it), so neither module imports the other's user."""

from __future__ import annotations

from typing import Any

from ..errors import InvalidArgument
from .trajectory import (
    PAPER_TRANSLATION_M,
    TRAJECTORIES,
    ConingTrajectory,
    ConstantRateTrajectory,
    CsvTrajectory,
    LevelTurnTrajectory,
    PaperTrajectory,
    StaticTrajectory,
    Trajectory,
    TrajectoryKind,
    TurntableTrajectory,
)
from .vehicle import vehicle_trajectory

__all__ = ["make_trajectory"]


def make_trajectory(kind: TrajectoryKind, **kw: Any) -> Trajectory:
    """Build a trajectory by name (``paper``, ``paper-translation``, ``coning``,
    ``static``, ``turntable``, ``level-turn``, ``constant-rate``, ``csv`` with
    ``path=``; the vehicles of :mod:`.vehicle`: ``fixed-wing``, ``fixed-wing-turn``,
    ``car``, ``car-brake``, ``car-roundabout``)."""
    if kind == "paper":
        return PaperTrajectory(**kw)
    if kind == "paper-translation":
        kw.setdefault("translation", PAPER_TRANSLATION_M)
        tr = PaperTrajectory(**kw)
        if tr.name != "paper-translation":
            raise InvalidArgument("paper-translation needs a non-zero translation")
        return tr
    if kind == "turntable":
        return TurntableTrajectory(**kw)
    if kind == "level-turn":
        return LevelTurnTrajectory(**kw)
    if kind == "coning":
        return ConingTrajectory(**kw)
    if kind == "static":
        return StaticTrajectory(**kw)
    if kind == "constant-rate":
        return ConstantRateTrajectory(**kw)
    if kind in ("fixed-wing", "fixed-wing-turn", "car", "car-brake", "car-roundabout"):
        return vehicle_trajectory(kind, **kw)
    if kind == "csv":
        if "path" not in kw:
            raise InvalidArgument("the csv trajectory needs path=")
        return CsvTrajectory(kw["path"])
    raise InvalidArgument(f"trajectory must be one of {TRAJECTORIES}, got {kind!r}")
