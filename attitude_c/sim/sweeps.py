"""Parameter sweeps and Monte Carlo studies on Dask (docs/sweep.md).

A *spec* (TOML) names a kind of run and the values to run it with:

* ``kind = "simulate"``: one run is one ``attitude simulate`` scenario. Any
  option of the simulator can be fixed, gridded or drawn at random: the
  options are the simulator's option table (:mod:`attitude_c.sim.options`,
  :func:`simulate_options`), which the command's parser is made from, so an
  option added there is sweepable with no change here. Each run's parameters
  become its configuration with ``SimConfig.from_dict``, the values checked
  by the same types as on the command line.
* ``kind = "recordings"``: one run is one attitude estimator, with one set of
  settings, on one recording (a BROAD trial, :mod:`attitude_c.broad`),
  scored with BROAD's error metric. The estimator is a callable registered
  by name (:func:`register_estimator`); the strapdown integrator is
  registered (``integrator``: ``method``, ``precision``).

Runs are expanded from the spec alone: every run's parameters, including
its seed and any random draw, are fixed before anything runs, and a run is
a pure function of its parameters, so results do not depend on where or in
which order runs execute. A run is keyed by a hash of its parameters; the
finished runs of a sweep are kept in a journal (``runs.jsonl`` in the
output folder), so a sweep started again with the same output folder runs
only what is missing.

Dask (``distributed``) runs the runs: a local cluster of worker processes
by default, an existing cluster by its scheduler address, or everything in
this process (``client="serial"``). dask, distributed and pandas are
optional dependencies (``pip install 'attitude-c[sweep]'``), imported when a
sweep runs.
"""

from __future__ import annotations

import contextlib
import hashlib
import inspect
import itertools
import json
import math
import os
import sys
import time
import traceback
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any, Literal

import numpy as np

from .._io import write_with
from ..core import Method, Precision
from ..errors import InvalidArgument
from .options import Option, by_name, parse, parse_value

__all__ = [
    "ESTIMATORS",
    "KINDS",
    "Run",
    "Spec",
    "SpecError",
    "integrate_trial",
    "load_spec",
    "plot_axis",
    "register_estimator",
    "simulate_options",
    "sweep",
    "unit_of",
]

Kind = Literal["simulate", "recordings"]
KINDS: tuple[Kind, ...] = ("simulate", "recordings")

#: The figure plotted when the spec names none, per kind.
DEFAULT_FIGURE = {"simulate": "err_attitude_angle_rms", "recordings": "total_deg"}
#: Parameters the summary aggregates over (replicates), per kind, when the spec names none.
DEFAULT_OVER = {"simulate": ("seed",), "recordings": ("seed", "trial")}
#: Parameter names the sweep itself sets.
RESERVED = ("seed", "case")

JOURNAL = "runs.jsonl"


class SpecError(InvalidArgument):
    """A spec that cannot be run: the message is one line naming what is wrong."""


# ---------------------------------------------------------------------------
# optional dependencies
# ---------------------------------------------------------------------------

def _need(module: str) -> Any:
    """Import an optional dependency or say what to install."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise ImportError(f"attitude sweep needs {module.split('.')[0]}: "
                          "pip install 'attitude-c[sweep]' (dask, distributed, pandas)") from exc


def _toml_loads(text: str) -> dict[str, Any]:
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover - Python 3.9/3.10
        try:
            import tomli as tomllib
        except ImportError as exc:
            raise ImportError("reading a sweep spec on Python < 3.11 needs tomli: "
                              "pip install 'attitude-c[sweep]'") from exc
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(f"not valid TOML: {exc}") from None
    except RecursionError:  # tomllib recurses per nesting level: 100,000 brackets are no spec
        raise SpecError("not valid TOML: arrays or tables nested too deep") from None


# ---------------------------------------------------------------------------
# the simulate option set: the simulator's option table
# ---------------------------------------------------------------------------

def _options() -> dict[str, Option]:
    """The simulator's options a spec can set (the table, :mod:`.options`; the sweep sets the seed)."""
    return {n: o for n, o in by_name().items() if n not in RESERVED}


#: Units of result and setting names by their ending (vectors' ``_0``.. stripped first).
_SUFFIX_UNITS = (("_rad_s", "rad/s"), ("_deg", "°"), ("_rad", "rad"), ("_dps", "°/s"), ("_s", "s"),
                 ("_hz", "Hz"), ("_ut", "µT"), ("_m_s2", "m/s²"))


def unit_of(spec: Spec, name: str) -> str | None:
    """The unit of a column of a sweep's table (a parameter or a figure), or None: a
    simulate option's own; ``err_*`` figures are summary.json's ``errors_rad``; else the
    name's ending (``total_deg``, ``link_time_s``, ``..._rad_s_0``)."""
    if spec.kind == "simulate" and name in _options():
        return _options()[name].unit
    if spec.kind == "simulate" and name.startswith("err_"):
        return "rad"
    base = name.rstrip("0123456789").removesuffix("_") if name[-1:].isdigit() else name
    return next((u for suffix, u in _SUFFIX_UNITS if base.endswith(suffix)), None)


def _labelled(spec: Spec, name: str) -> str:
    unit = unit_of(spec, name)
    return f"{name} ({unit})" if unit else name


def simulate_options() -> dict[str, Option]:
    """The simulator's options a spec can set (those of ``attitude simulate`` but the
    seed, which the sweep sets, and how a run is kept), by parameter name."""
    return dict(_options())


def _option_name(name: str) -> str:
    return name.strip().lstrip("-").replace("-", "_")


def _argv_value(v: Any) -> str:
    """A value as its command-line text (a table cell)."""
    if isinstance(v, bool):
        return str(v).lower()
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, (list, tuple)):
        return ",".join(_argv_value(x) for x in v)
    return str(v)


def _jsonable(v: Any) -> Any:
    if isinstance(v, tuple):
        return [_jsonable(x) for x in v]
    if isinstance(v, list):
        return [_jsonable(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    return v


# ---------------------------------------------------------------------------
# recordings: estimators over BROAD trials
# ---------------------------------------------------------------------------

#: Estimators of the ``recordings`` kind, by name: ``fn(trial, **settings)`` returns the
#: attitude (N, 4) at every sample of the trial, or ``(q (M, 4), index (M,))`` with the
#: sample index of each attitude. A setting named ``seed`` gets the run's seed.
ESTIMATORS: dict[str, Callable[..., Any]] = {}


def register_estimator(name: str, fn: Callable[..., Any]) -> None:
    """Make ``fn`` available as ``estimator = "name"`` in a ``recordings`` spec.

    The attitude filter plugs in with one line::

        register_estimator("ahrs", lambda trial, **s: attitude_c.ahrs(
            trial.gyr, trial.acc, trial.mag, rate=trial.rate, **s))

    Dask ships the callable to the workers with each run (it must pickle:
    a module-level function or a lambda defined in an importable module).
    """
    if not callable(fn):
        raise TypeError(f"fn must be callable, got {type(fn).__name__}")
    ESTIMATORS[name] = fn


def integrate_trial(trial: Any, method: Method = "rv3", precision: Precision = "f64") -> tuple[np.ndarray, np.ndarray]:
    """The strapdown integrator (gyro only) on a BROAD trial.

    Starts at the first sample with a valid reference, from the reference
    attitude there (a gyro alone cannot know its initial attitude); the
    increment over each sample interval is the trapezoid of the two rate
    samples times 1/rate (``rk4``: the rates themselves, two intervals per
    step). Returns the attitudes and the sample index each one belongs to.
    """
    from .. import core, names

    ok = np.flatnonzero(np.isfinite(trial.quat).all(axis=1))
    if ok.size == 0:
        raise InvalidArgument(f"trial {trial.name}: no sample has a reference attitude to start from")
    s0 = int(ok[0])
    q0 = trial.quat[s0]
    gyr = trial.gyr[s0:]
    dt = 1.0 / trial.rate
    if method == "rk4":
        q = core.integrate_rates(gyr, dt, method="rk4", q0=q0, precision=precision)
        step = 2
    else:
        inc = 0.5 * (gyr[1:] + gyr[:-1]) * dt
        if precision == "f32":
            inc = inc.astype(np.float32)
        q = core.integrate(inc, method=method, q0=q0, precision=precision)
        step = names.samples_per_update(method)
    q = np.asarray(q, dtype=np.float64)
    return q, s0 + step * (np.arange(len(q)) + 1)


register_estimator("integrator", integrate_trial)


def ahrs_trial(trial: Any, six_axis: bool = False, precision: Literal["f64", "f32"] = "f64",
               **settings: Any) -> np.ndarray:
    """The attitude filter (:func:`attitude_c.ahrs_filter.ahrs`, docs/ahrs.md) on a BROAD trial.

    It aligns itself from the first samples (no reference needed); ``six_axis``
    leaves the magnetometer out; every other setting is a filter setting
    (``acc_noise``, ``rest_noise``, ...: ``attitude_c.ahrs_filter.default_settings()``).
    """
    from ..ahrs_filter import ahrs

    return ahrs(trial.gyr, trial.acc, None if six_axis else trial.mag, rate=trial.rate,
                precision=precision, **settings)


def _ahrs_settings() -> frozenset[str]:
    from ..ahrs_filter import default_settings

    return frozenset(default_settings()) | {"six_axis", "precision"}


ahrs_trial.settings = _ahrs_settings()  # type: ignore[attr-defined]
register_estimator("ahrs", ahrs_trial)


@lru_cache(maxsize=4)
def _trial(path: str) -> Any:
    from .. import broad

    return broad.load_trial(path)


def _trial_files(folder: Path) -> dict[str, Path]:
    return {p.stem: p for p in sorted(folder.glob("*.mat"))}


def _accepts(fn: Callable[..., Any], name: str) -> bool | None:
    """Whether fn takes keyword ``name`` (None: it takes any keyword, or cannot be inspected).

    A function taking ``**settings`` may list the names it knows in a ``settings`` attribute.
    """
    known = getattr(fn, "settings", None)
    if known is not None:
        return name in known
    try:
        sig = inspect.signature(fn)
    except (TypeError, ValueError):
        return None
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in sig.parameters.values()):
        return None
    p = sig.parameters.get(name)
    return p is not None and p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)


# ---------------------------------------------------------------------------
# the spec
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class Run:
    """One run: its key (hash of kind and parameters) and its parameters."""

    key: str
    params: dict[str, Any]


@dataclass
class Spec:
    """A parsed and expanded sweep spec (:func:`load_spec`)."""

    name: str
    kind: Kind
    runs: list[Run]
    axes: list[str]                 #: swept parameters, in the spec's order (plots)
    random_axes: list[str]          #: of those, the randomly drawn ones
    over: list[str]                 #: replicate parameters the summary aggregates over
    figure: str                     #: the figure plotted
    text: str = ""                  #: the spec's TOML (copied into the output folder)
    source: Path | None = None      #: the spec file
    data: Path | None = None        #: recordings: the trials' folder
    retries: int = 2
    chunk: int = 1
    estimators: dict[str, Callable[..., Any]] = field(default_factory=dict)

    @property
    def params(self) -> list[str]:
        """Every parameter any run sets, in order of first appearance."""
        seen: dict[str, None] = {}
        for r in self.runs:
            for k in r.params:
                seen.setdefault(k, None)
        return list(seen)


_SWEEP_KEYS = {"name", "kind", "seeds", "data", "trials", "summary_over", "figure", "retries", "chunk"}
_TOP_KEYS = {"sweep", "fixed", "grid", "random", "cases", "exclude"}


def _key(kind: str, params: Mapping[str, Any]) -> str:
    blob = json.dumps({"kind": kind, "params": params}, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


_DISTRIBUTIONS = ("uniform", "log_uniform", "int", "normal", "choice")


def _draw(name: str, dist: Any, rng: np.random.Generator, n: int) -> list[Any]:
    if not isinstance(dist, dict) or len(dist) != 1 or next(iter(dist)) not in _DISTRIBUTIONS:
        raise SpecError(f"[random] {name}: give one distribution, e.g. {{uniform = [lo, hi]}}, "
                        "{log_uniform = [lo, hi]}, {int = [lo, hi]}, {normal = [mean, sd]}, {choice = [...]}")
    (how, arg), = dist.items()
    if how == "choice":
        if not isinstance(arg, list) or not arg:
            raise SpecError(f"[random] {name}: choice needs a non-empty list")
        return [arg[i] for i in rng.integers(0, len(arg), n)]
    if not (isinstance(arg, list) and len(arg) == 2 and all(isinstance(x, (int, float)) for x in arg)):
        raise SpecError(f"[random] {name}: {how} needs two numbers, got {arg!r}")
    a, b = float(arg[0]), float(arg[1])
    if how == "uniform" and a < b:
        return [float(x) for x in rng.uniform(a, b, n)]
    if how == "log_uniform" and 0 < a < b:
        return [float(x) for x in np.exp(rng.uniform(math.log(a), math.log(b), n))]
    if how == "int" and a <= b and a == int(a) and b == int(b):
        return [int(x) for x in rng.integers(int(a), int(b) + 1, n)]
    if how == "normal" and b > 0:
        return [float(x) for x in rng.normal(a, b, n)]
    raise SpecError(f"[random] {name}: bad {how} {arg!r} (uniform/log_uniform: lo < hi, log_uniform lo > 0; "
                    "int: integers lo <= hi; normal: sd > 0; choice: a list)")


def _table(doc: Mapping[str, Any], name: str) -> dict[str, Any]:
    t = doc.get(name, {})
    if not isinstance(t, dict):
        raise SpecError(f"[{name}] must be a table")
    return t


def _check_seeds(seeds_v: Any, where: str) -> Sequence[int]:
    """A seeds value (a count >= 1 or a list of integers >= 0) as the seeds (a count:
    ``range``, so that its size is known before anything is made of it)."""
    if isinstance(seeds_v, bool) or not (isinstance(seeds_v, int) and seeds_v >= 1 or isinstance(seeds_v, list)
                                          and seeds_v and all(isinstance(s, int) and not isinstance(s, bool)
                                                              and 0 <= s < 2**63 for s in seeds_v)):
        raise SpecError(f"{where} must be a count >= 1 or a list of integers >= 0, got {seeds_v!r}")
    return range(seeds_v) if isinstance(seeds_v, int) else list(seeds_v)


def _override_note(sets: Mapping[str, Any], seeds: Any, limit: int | None) -> str:
    """The command-line cuts of a sweep, as TOML comments for the spec.toml it leaves."""
    parts = [f"--set {k}={json.dumps(_jsonable(v))}" for k, v in sets.items()]
    if seeds is not None:
        parts.append(f"--seeds {json.dumps(seeds)}")
    if limit is not None:
        parts.append(f"--limit {limit}")
    return f"\n# run with: {' '.join(parts)}\n" if parts else ""


#: The most runs a spec may expand to (before exclusions), unless the caller allows more
#: (``load_spec(max_runs=...)``, ``attitude sweep --max-runs``): each run's parameters are
#: held in memory, about 1.3 KB a run, so the default bounds a spec's expansion by ~130 MB.
MAX_RUNS = 100_000


def load_spec(spec: str | os.PathLike[str] | Mapping[str, Any], *, base: Path | None = None,
              sets: Mapping[str, Any] | None = None, seeds: int | list[int] | None = None,
              limit: int | None = None, max_runs: int = MAX_RUNS) -> Spec:
    """Read and expand a spec: a TOML file's path, or the parsed document.

    The spec can be cut down without editing it (``attitude sweep --set``,
    ``--seeds``, ``--limit``): ``sets`` pins parameters for every run (over the
    spec's fixed, grid, random and case values of the same names; a recordings
    spec's ``trial`` replaces ``[sweep] trials``), ``seeds`` replaces ``[sweep]
    seeds`` (a count or a list), ``limit`` keeps the first runs in spec order.
    They go through the spec's own checks, errors naming ``--set NAME``.

    The runs are counted before anything is expanded or drawn: a spec of more
    than ``max_runs`` (cases × grid points × draws × seeds) is refused with the
    count (``limit`` does not lift it: the whole spec fixes every run's draws).

    Raises :class:`SpecError` (one line) for anything that cannot run:
    unknown keys or options, bad values (checked by the simulator's option
    table and ``SimConfig.validate``), unknown estimators or trials, too many
    runs; OSError when the spec file cannot be read.
    """
    sets = dict(sets or {})
    for what, v in (("--limit", limit), ("max_runs", max_runs)):
        if v is not None and (isinstance(v, bool) or not isinstance(v, int) or v < 1):
            raise SpecError(f"{what} must be an integer >= 1, got {v!r}")
    doc, text, source, base = _read_spec(spec, base)
    head, kind = _head(doc)
    name = str(head.get("name") or (source.stem if source else "sweep"))
    seed_list = _check_seeds(head.get("seeds", 1), "[sweep] seeds") if seeds is None else \
        _check_seeds(seeds, "--seeds")
    if text:
        text += _override_note(sets, seeds, limit)
    retries, chunk = _retries_chunk(head)
    parts = _parts(doc, kind, base, sets)
    if kind == "recordings" and "trial" in parts.pinned:
        t = parts.pinned.pop("trial")
        head = {**head, "trials": t if isinstance(t, (str, list)) else str(t)}
    for k in parts.pinned:  # pinned: off the grid (the draws stay as drawn, so the others' do not change)
        parts.grid.pop(k, None)
    data, grid = _recordings(kind, head, base, parts)
    _check_size(parts, grid, len(seed_list), max_runs)
    drawn = _drawn(parts)
    estimators: dict[str, Callable[..., Any]] = {}
    runs = _expand(kind, parts, grid, drawn, seed_list, estimators)[:limit]
    random_axes = sorted(k for k in parts.rnd if k not in parts.pinned)
    over, axes = _axes(kind, head, parts, grid, random_axes, runs, limit)
    figure = str(head.get("figure", DEFAULT_FIGURE[kind]))
    return Spec(name=name, kind=kind, runs=runs, axes=[a for a in axes if a not in over], random_axes=random_axes,
                over=over, figure=figure, text=text, source=source, data=data, retries=retries, chunk=chunk,
                estimators=estimators)


def _read_spec(spec: str | os.PathLike[str] | Mapping[str, Any],
               base: Path | None) -> tuple[dict[str, Any], str, Path | None, Path]:
    """(document, its TOML text or "", the file or None, the folder paths are relative to)."""
    if isinstance(spec, Mapping):
        return dict(spec), "", None, base or Path.cwd()
    source = Path(spec)
    text = source.read_text()  # OSError (names the file): an OS error, not a spec error
    return _toml_loads(text), text, source, base or source.parent


def _head(doc: Mapping[str, Any]) -> tuple[dict[str, Any], Kind]:
    """The [sweep] table, its keys checked, and the spec's kind."""
    unknown = set(doc) - _TOP_KEYS
    if unknown:
        raise SpecError(f"unknown section(s) {sorted(unknown)}; a spec has {sorted(_TOP_KEYS)}")
    head = _table(doc, "sweep")
    bad = set(head) - _SWEEP_KEYS
    if bad:
        raise SpecError(f"[sweep] unknown key(s) {sorted(bad)}; known: {sorted(_SWEEP_KEYS)}")
    kind = head.get("kind", "simulate")
    if kind not in KINDS:
        raise SpecError(f"[sweep] kind must be one of {list(KINDS)}, got {kind!r}")
    return head, kind


def _retries_chunk(head: Mapping[str, Any]) -> tuple[int, int]:
    retries, chunk = head.get("retries", 2), head.get("chunk", 1)
    for k, v, lo in (("retries", retries, 0), ("chunk", chunk, 1)):
        if isinstance(v, bool) or not isinstance(v, int) or v < lo:
            raise SpecError(f"[sweep] {k} must be an integer >= {lo}, got {v!r}")
    return retries, chunk


@dataclass
class _Parts:
    """A spec's parameter sets before expansion (names normalized, values checked alone)."""

    fixed: dict[str, Any]
    grid: dict[str, list[Any]]
    rnd: dict[str, Any]
    cases: list[dict[str, Any]]
    excl: list[dict[str, Any]]
    pinned: dict[str, Any]
    draws: int
    rseed: int


def _parts(doc: Mapping[str, Any], kind: Kind, base: Path, sets: Mapping[str, Any]) -> _Parts:
    fixed, grid, rnd = _table(doc, "fixed"), _table(doc, "grid"), dict(_table(doc, "random"))
    cases, excl = doc.get("cases", [{}]), doc.get("exclude", [])
    for nm, v in (("cases", cases), ("exclude", excl)):
        if not (isinstance(v, list) and all(isinstance(x, dict) for x in v)):
            raise SpecError(f"[[{nm}]] must be an array of tables")
    for k, v in grid.items():
        if not isinstance(v, list) or not v:
            raise SpecError(f"[grid] {k}: give a non-empty list of values, got {v!r}")
    draws = rnd.pop("draws", 0 if not rnd else None)
    rseed = rnd.pop("seed", 0)
    if rnd and (isinstance(draws, bool) or not isinstance(draws, int) or draws < 1):
        raise SpecError(f"[random] draws must be an integer >= 1, got {draws!r}")
    if isinstance(rseed, bool) or not isinstance(rseed, int) or rseed < 0:
        raise SpecError(f"[random] seed must be an integer >= 0, got {rseed!r}")
    parts = _Parts(_norm(kind, base, "fixed", fixed), _norm(kind, base, "grid", grid), _norm(kind, base, "random", rnd),
                   [_norm(kind, base, "cases", c) for c in cases], [_norm(kind, base, "exclude", e) for e in excl],
                   _norm(kind, base, "set", sets), draws, rseed)
    clash = set(parts.grid) & set(parts.rnd)
    if clash:
        raise SpecError(f"parameter(s) {sorted(clash)} both in [grid] and [random]")
    for k, v in parts.pinned.items() if kind == "simulate" else ():
        try:  # each value alone, through the option table: the error names the key
            parse_value(k, v)
        except (ValueError, TypeError) as exc:
            raise SpecError(f"--set {k}: {exc}") from None
    return parts


def _norm(kind: Kind, base: Path, section: str, d: Mapping[str, Any]) -> dict[str, Any]:
    """A section's parameters under their names (``cone-angle`` → ``cone_angle``), paths
    from the spec's folder; SpecError for a name the kind does not have or reserves."""
    out = {}
    where = "--set" if section == "set" else f"[{section}]"
    for k, v in d.items():
        n = _option_name(k)
        if section == "cases" and n == "label":
            n, v = "case", str(v)
        if n == "seed" and section != "exclude":
            raise SpecError(f"{where} seed: the sweep sets the seed; use [sweep] seeds = N or [list] (or --seeds)")
        if n == "case" and section not in ("cases", "exclude"):
            raise SpecError(f"{where} case: reserved for the label of a [[cases]] entry")
        if kind == "simulate" and n not in _options() and n not in RESERVED:
            raise SpecError(f"{where} {k}: not an option of attitude simulate (sweepable: "
                            f"{', '.join(sorted(_options()))})")
        if n.endswith(("_file", "_path")) and section != "exclude":  # a path: from the spec's folder
            v = [_path(base, x) for x in v] if section == "grid" and isinstance(v, list) else _path(base, v)
        out[n] = v
    return out


def _recordings(kind: Kind, head: Mapping[str, Any], base: Path,
                parts: _Parts) -> tuple[Path | None, dict[str, list[Any]]]:
    """A recordings spec's folder of trials and the grid with ``trial`` first (the
    simulate kind: None and the grid as it is)."""
    if kind != "recordings":
        if head.get("data") is not None or head.get("trials") is not None:
            raise SpecError("[sweep] data and trials belong to kind = \"recordings\"")
        return None, parts.grid
    from .. import broad

    d = head.get("data")
    folder = (base / d) if d else broad.default_dir()
    if folder is None or not folder.is_dir():
        raise SpecError(f"[sweep] data: no folder of recordings at {str(folder)!r}")
    data = folder.resolve()
    trial_files = _trial_files(data)
    if not trial_files:
        raise SpecError(f"[sweep] data: no .mat recordings in {str(data)!r}")
    trials = head.get("trials", sorted(trial_files))
    if isinstance(trials, str):
        trials = [t for t in sorted(trial_files) if Path(t).match(trials)]
    if not isinstance(trials, list) or not trials:
        raise SpecError("[sweep] trials: give a list of trial names or a glob matching some")
    missing = [t for t in trials if t not in trial_files]
    if missing:
        raise SpecError(f"[sweep] trials: not in {str(data)!r}: {missing}")
    if "trial" in parts.grid or "trial" in parts.fixed:
        raise SpecError("trial: list the recordings in [sweep] trials")
    return data, {"trial": list(trials), **parts.grid}


def _check_size(parts: _Parts, grid: Mapping[str, list[Any]], n_seeds: int, max_runs: int) -> None:
    """Refuse a spec of more than ``max_runs`` runs, counted before anything is expanded."""
    factors = [(len(parts.cases), "cases"), *((len(v), f"{k} values") for k, v in grid.items()),
               (max(parts.draws, 1), "draws"), (n_seeds, "seeds")]
    total = math.prod(n for n, _ in factors)
    if total > max_runs:
        how = " × ".join(f"{n:,} {what}" for n, what in factors if n > 1)
        raise SpecError(f"the spec expands to {total:,} runs ({how}), more than the limit of {max_runs:,}: "
                        "use fewer seeds, draws or grid values (--seeds, --set), or raise the limit "
                        "(attitude sweep --max-runs N; load_spec(max_runs=N))")


def _drawn(parts: _Parts) -> list[dict[str, Any]]:
    """The random draws: one dict of drawn values per draw ([{}]: nothing drawn)."""
    if not parts.rnd:
        return [{}]
    rng = np.random.default_rng(parts.rseed)
    cols = {k: _draw(k, parts.rnd[k], rng, parts.draws) for k in sorted(parts.rnd)}
    return [{k: cols[k][i] for k in sorted(parts.rnd)} for i in range(parts.draws)]


def _expand(kind: Kind, parts: _Parts, grid: Mapping[str, list[Any]], drawn: list[dict[str, Any]],
            seed_list: Sequence[int], estimators: dict[str, Callable[..., Any]]) -> list[Run]:
    """cases × grid × draws × seeds, each point checked (:func:`_canonical`), less the
    excluded and the repeated ones."""
    gkeys = list(grid)
    runs: list[Run] = []
    seen: set[str] = set()
    for case in parts.cases:
        for combo in itertools.product(*(grid[k] for k in gkeys)):
            for draw in drawn:
                # a case pins what it names: over the grid and the draws
                point = {**parts.fixed, **dict(zip(gkeys, combo)), **draw, **case, **parts.pinned}
                if kind == "recordings":
                    point.setdefault("estimator", "integrator")
                live = [s for s in seed_list if not any(all({**point, "seed": s}.get(k, _MISSING) == v
                                                        for k, v in e.items()) for e in parts.excl)]
                if not live:
                    continue
                canon = _canonical(kind, point, estimators)
                for s in live:
                    params = {**canon, "seed": s}
                    key = _key(kind, params)
                    if key not in seen:
                        seen.add(key)
                        runs.append(Run(key, params))
    if not runs:
        raise SpecError("the spec expands to no run (everything excluded?)")
    return runs


def _axes(kind: Kind, head: Mapping[str, Any], parts: _Parts, grid: Mapping[str, list[Any]],
          random_axes: list[str], runs: list[Run], limit: int | None) -> tuple[list[str], list[str]]:
    """(the replicate parameters the summary aggregates over, the swept parameters)."""
    axes = [k for k in grid if len({json.dumps(_jsonable(v)) for v in grid[k]}) > 1] + random_axes
    if len(parts.cases) > 1:
        axes.insert(0, "case")
    if limit is not None:  # the axes the runs kept still sweep
        axes = [a for a in axes if len({json.dumps(r.params.get(a)) for r in runs}) > 1]
    over_v = head.get("summary_over", list(DEFAULT_OVER[kind]))
    if not (isinstance(over_v, list) and all(isinstance(x, str) for x in over_v)):
        raise SpecError(f"[sweep] summary_over must be a list of parameter names, got {over_v!r}")
    return [_option_name(x) for x in over_v], axes


_MISSING = object()


def _canonical(kind: str, point: dict[str, Any], estimators: dict[str, Callable[..., Any]]) -> dict[str, Any]:
    """The run's parameters as the run will see them; SpecError if they cannot run."""
    if kind == "simulate":
        from .chain import SimConfig
        from .configure import build

        try:  # each value alone, then the configuration's own checks: what cannot run is a spec error
            typed = parse({k: v for k, v in point.items() if k not in RESERVED})
            SimConfig(**build(typed)).validate()
        except (ValueError, TypeError) as exc:
            raise SpecError(f"run {_show(point)}: {exc}") from None
        out = {}
        for k, v in point.items():
            c = v if k == "case" else _jsonable(typed[k])
            try:  # the parsed value when it has a JSON form, else the spec's own
                json.dumps(c)
            except (TypeError, ValueError):
                c = _jsonable(v)
            out[k] = c
        return out
    name = point["estimator"]
    fn = ESTIMATORS.get(name)
    if fn is None:
        raise SpecError(f"estimator {name!r} is not registered (registered: {', '.join(sorted(ESTIMATORS))})")
    estimators[name] = fn
    for k in point:
        if k not in ("trial", "estimator", "case") and _accepts(fn, k) is False:
            raise SpecError(f"estimator {name!r} has no setting {k!r}")
    return {k: _jsonable(v) for k, v in point.items()}


def _path(base: Path, v: Any) -> Any:
    return str((base / v).resolve()) if isinstance(v, str) and v else v


def _show(point: Mapping[str, Any]) -> str:
    return "{" + ", ".join(f"{k}={v!r}" for k, v in point.items()) + "}"


# ---------------------------------------------------------------------------
# one run (executed on a worker)
# ---------------------------------------------------------------------------

#: summary.json entries that are not figures of the run: parameters, constants, wall time
_NOT_FIGURES = ("attitude_c_version", "parameters", "paper_maxima_rad", "backends", "elapsed_s")


def _flat_figures(summary: Mapping[str, Any]) -> dict[str, float]:
    """Every number of a run's summary.json, flattened: ``err_<angle>_<stat>`` for
    ``errors_rad``, ``<section>_<key>[_<key>...]`` for the rest, 3-vectors as ``_0``,
    ``_1``, ``_2``; parameters, constants and wall times left out (they are not results,
    and a wall time would make the table depend on scheduling)."""
    figs: dict[str, float] = {}

    def walk(prefix: str, v: Any) -> None:
        if isinstance(v, bool) or v is None:
            return
        if isinstance(v, (int, float)):
            figs[prefix] = float(v)
        elif isinstance(v, Mapping):
            for k, x in v.items():
                if "elapsed" in k or "wall" in k or (prefix == "link" and k in ("seed", "ber")):
                    continue
                walk(f"{prefix}_{k}" if prefix else str(k), x)
        elif isinstance(v, (list, tuple)) and len(v) == 3 and all(
                isinstance(x, (int, float)) and not isinstance(x, bool) for x in v):
            for i, x in enumerate(v):
                figs[f"{prefix}_{i}"] = float(x)

    walk("err", summary.get("errors_rad", {}))
    walk("", {k: v for k, v in summary.items() if k not in _NOT_FIGURES and k != "errors_rad"})
    return figs


def _run_simulate(params: Mapping[str, Any]) -> dict[str, float]:
    from .chain import SimConfig, simulate

    res = simulate(SimConfig.from_dict({k: v for k, v in params.items() if k != "case"}))
    return _flat_figures(res.summary)


def _run_recording(params: Mapping[str, Any], data: str, fn: Callable[..., Any]) -> dict[str, float]:
    from .. import broad

    trial = _trial(str(Path(data) / f"{params['trial']}.mat"))
    settings = {k: v for k, v in params.items() if k not in ("trial", "estimator", "case", "seed")}
    if "seed" in params and _accepts(fn, "seed"):  # only to an estimator that names the setting
        settings["seed"] = params["seed"]
    out = fn(trial, **settings)
    if isinstance(out, tuple):
        q, idx = np.asarray(out[0], dtype=np.float64), np.asarray(out[1], dtype=np.int64)
    else:
        q = np.asarray(out, dtype=np.float64)
        idx = np.arange(len(q))
    if q.ndim != 2 or q.shape[1] != 4 or idx.shape != (len(q),) or (len(idx) and (idx.min() < 0
                                                                                 or idx.max() >= trial.n)):
        raise InvalidArgument(f"estimator returned attitudes of shape {q.shape} with indices "
                              f"{idx.shape}: expected (M, 4) and (M,) within the trial's {trial.n} samples")
    f = broad.errors(q, trial.quat[idx], trial.movement[idx])
    return {"total_deg": f.total, "heading_deg": f.heading, "inclination_deg": f.inclination,
            "samples": float(f.samples)}


def _version() -> str:
    import attitude_c

    return str(attitude_c.__version__)


def run_chunk(kind: str, runs: Sequence[tuple[str, dict[str, Any]]], data: str | None,
              estimators: Mapping[str, Callable[..., Any]]) -> list[dict[str, Any]]:
    """Execute runs; one record each. A run that raises is recorded with its error."""
    out = []
    for key, params in runs:
        t0 = time.perf_counter()
        rec: dict[str, Any] = {"key": key, "params": params, "figures": {}, "error": None}
        try:
            if kind == "simulate":
                rec["figures"] = _run_simulate(params)
            else:
                rec["figures"] = _run_recording(params, str(data), estimators[params["estimator"]])
        except Exception as exc:  # noqa: BLE001 - any failure of one run is its result
            tb = traceback.extract_tb(exc.__traceback__)
            where = f" ({Path(tb[-1].filename).name}:{tb[-1].lineno})" if tb else ""
            rec["error"] = f"{type(exc).__name__}: {exc}{where}"
        rec["elapsed_s"] = time.perf_counter() - t0
        rec["attitude_c_version"] = _version()
        out.append(rec)
    return out


# ---------------------------------------------------------------------------
# the journal (resume) and atomic files
# ---------------------------------------------------------------------------

def read_journal(path: Path, *, repair: bool = False) -> dict[str, dict[str, Any]]:
    """The finished runs recorded in ``path``, by key (later lines win; a torn last
    line is ignored, and with ``repair`` cut off so that appends start clean: only
    the sweep that holds the folder's lock repairs)."""
    done: dict[str, dict[str, Any]] = {}
    if not path.exists():
        return done
    raw = path.read_bytes()
    end = raw.rfind(b"\n") + 1
    if repair and end < len(raw):  # killed while writing a line
        with open(path, "r+b") as f:
            f.truncate(end)
    for line in raw[:end].splitlines():
        try:
            rec = json.loads(line)
        except ValueError:
            continue
        if isinstance(rec, dict) and "key" in rec:
            done[rec["key"]] = rec
    return done


@contextlib.contextmanager
def _named(path: Path) -> Iterator[None]:
    """An OSError writing ``path`` names it (a full disk's ENOSPC from a write or an
    fsync carries no file name, or the temporary one)."""
    try:
        yield
    except OSError as exc:
        if exc.filename is not None and Path(os.fsdecode(exc.filename)).name == path.name:
            raise
        raise type(exc)(exc.errno, exc.strerror or str(exc), str(path)) from exc


class _Journal:
    def __init__(self, path: Path) -> None:
        self.path = path
        self.f = open(path, "a", encoding="utf-8")  # noqa: SIM115 - held open for the whole sweep
        self.last_sync = time.monotonic()

    def write(self, recs: Iterable[dict[str, Any]]) -> None:
        with _named(self.path):
            for r in recs:
                self.f.write(json.dumps(r, separators=(",", ":"), allow_nan=True) + "\n")
            self.f.flush()
            if time.monotonic() - self.last_sync > 1.0:
                os.fsync(self.f.fileno())
                self.last_sync = time.monotonic()

    def close(self) -> None:
        try:
            with _named(self.path):
                self.f.flush()
                os.fsync(self.f.fileno())
        finally:
            with contextlib.suppress(OSError):
                self.f.close()


class _Lock:
    """An exclusive advisory lock on the output folder (one sweep writes a journal at a time)."""

    def __init__(self, folder: Path) -> None:
        self.f = open(folder / ".sweep.lock", "a")  # noqa: SIM115 - held for the whole sweep
        try:
            import fcntl
        except ImportError:  # pragma: no cover - not POSIX: no lock
            return
        try:
            fcntl.flock(self.f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            self.f.close()
            raise InvalidArgument(f"out: another sweep is running in {str(folder)!r} (it holds "
                                  f"{str(folder / '.sweep.lock')!r})") from None

    def release(self) -> None:
        self.f.close()


# ---------------------------------------------------------------------------
# execution
# ---------------------------------------------------------------------------

def _chunks(items: Sequence[Run], n: int) -> Iterator[list[tuple[str, dict[str, Any]]]]:
    for i in range(0, len(items), n):
        yield [(r.key, r.params) for r in items[i:i + n]]


def default_workers() -> int:
    """Worker processes of the default local cluster: the CPUs this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def _engine(client: Any, workers: int | None) -> tuple[Any, Callable[[], None], str]:
    """(client or None for serial, close(), description)."""
    if isinstance(client, str) and client == "serial":
        return None, lambda: None, "serial (this process)"
    distributed = _need("distributed")
    if client is None:
        n = workers or default_workers()
        import logging

        cluster = distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                           dashboard_address=":0", silence_logs=logging.CRITICAL)
        c = distributed.Client(cluster)

        def close() -> None:
            c.close()
            cluster.close()
        return c, close, f"local cluster, {n} worker process(es)"
    if isinstance(client, str):
        try:
            c = distributed.Client(client, timeout="15s")
        except (OSError, TimeoutError) as exc:
            raise ConnectionError(f"no Dask scheduler at {client}: {exc}") from None
        n = len(c.scheduler_info().get("workers", {}))
        return c, c.close, f"scheduler {client}, {n} worker(s)"
    return client, lambda: None, f"Dask client {getattr(client, 'scheduler', '')}"


def _execute(spec: Spec, todo: list[Run], client: Any, journal: _Journal,
             progress: Callable[[int], None]) -> int:
    data = str(spec.data) if spec.data else None
    chunks = list(_chunks(todo, spec.chunk))
    done = 0
    if client is None:
        for ch in chunks:
            recs = run_chunk(spec.kind, ch, data, spec.estimators)
            journal.write(recs)
            done += len(recs)
            progress(len(recs))
        return done
    distributed = _need("distributed")
    nthreads = max(1, sum(client.nthreads().values()))
    window = max(8, 4 * nthreads)  # futures in flight: bounded, so 10^6 runs do not flood the scheduler
    it = iter(chunks)
    pending: dict[Any, list[tuple[str, dict[str, Any]]]] = {}

    def submit(ch: list[tuple[str, dict[str, Any]]]) -> Any:
        fut = client.submit(run_chunk, spec.kind, ch, data, spec.estimators,
                            key=f"attitude-sweep-{ch[0][0]}-{len(ch)}", retries=spec.retries, pure=False)
        pending[fut] = ch
        return fut

    ac = distributed.as_completed([submit(ch) for ch in itertools.islice(it, window)])
    try:
        for fut in ac:
            ch = pending.pop(fut)
            try:
                recs = fut.result()
            except Exception as exc:  # noqa: BLE001 - the engine gave up (e.g. KilledWorker too often)
                recs = [{"key": k, "params": p, "figures": {}, "elapsed_s": float("nan"),
                         "attitude_c_version": _version(), "error": f"{type(exc).__name__}: {exc}"}
                        for k, p in ch]
            fut.release()
            journal.write(recs)
            done += len(recs)
            progress(len(recs))
            nxt = next(it, None)
            if nxt is not None:
                ac.add(submit(nxt))
    finally:
        for f in list(pending):
            f.cancel()
    return done


# ---------------------------------------------------------------------------
# results: table, summary, plots
# ---------------------------------------------------------------------------

def _cell(v: Any) -> Any:
    if isinstance(v, list):
        return ",".join(_argv_value(x) for x in v)
    return v


def results_table(spec: Spec, records: Mapping[str, dict[str, Any]]) -> Any:
    """One row per run of ``spec`` (in spec order): key, every parameter, every figure,
    error, elapsed_s, attitude_c_version."""
    pd = _need("pandas")
    params = spec.params
    figs: dict[str, None] = {}
    for r in spec.runs:
        rec = records.get(r.key)
        if rec:
            for k in rec["figures"]:
                figs.setdefault(k, None)
    rows = []
    for r in spec.runs:
        rec = records.get(r.key)
        if rec is None:
            continue
        row: dict[str, Any] = {"key": r.key}
        row.update({p: _cell(r.params.get(p)) for p in params})
        row.update({f: rec["figures"].get(f, math.nan) for f in figs})
        row["error"] = rec.get("error") or ""
        row["elapsed_s"] = rec.get("elapsed_s", math.nan)
        row["attitude_c_version"] = rec.get("attitude_c_version", "")
        rows.append(row)
    cols = ["key", *params, *figs, "error", "elapsed_s", "attitude_c_version"]
    return pd.DataFrame(rows, columns=cols)


def figure_columns(df: Any, spec: Spec) -> list[str]:
    skip = {"key", "error", "elapsed_s", "attitude_c_version", *spec.params}
    return [c for c in df.columns if c not in skip]


def summarize(df: Any, spec: Spec) -> Any:
    """Per grid point (every parameter but the replicates ``spec.over``) and figure:
    runs, n (finished without error), mean, std, min, p5, p50, p95, max. Long format."""
    pd = _need("pandas")
    figs = figure_columns(df, spec)
    group = [p for p in spec.params if p not in spec.over]
    # a parameter some runs do not set (a case's) is "" there: NaN would not group reliably
    base = df.assign(**{p: df[p].astype(object).where(df[p].notna(), "") for p in group if df[p].isna().any()})
    if not figs:
        return pd.DataFrame(columns=[*group, "figure", "runs", "n"])
    long = base.melt(id_vars=group or None, value_vars=figs, var_name="figure", value_name="value")
    keys = [*group, "figure"]
    g = long.groupby(keys, sort=False)["value"]
    out = g.agg(runs="size", n="count", mean="mean", std="std", min="min", max="max")
    q = g.quantile([0.05, 0.5, 0.95]).unstack()
    q.columns = ["p5", "p50", "p95"]
    out = out.join(q)[["runs", "n", "mean", "std", "min", "p5", "p50", "p95", "max"]]
    return out.reset_index()


def _is_num(s: Any) -> bool:
    pd = _need("pandas")
    return bool(pd.api.types.is_numeric_dtype(s))


_MAX_PANELS = 9
_MAX_LINES = 10


def _band(ax: Any, sub: Any, axis: str, fig_col: str, numeric: bool, pos: dict[Any, int], label: str,
          dodge: float = 0.0) -> None:
    """The median and 5–95 % band of ``fig_col`` per value of ``axis``: a line and a band
    over a numeric axis; over categories (no order, nothing between them) markers with
    5–95 % bars, moved sideways by ``dodge`` so that several lines stay apart."""
    st = sub.groupby(axis, sort=True)[fig_col].quantile([0.05, 0.5, 0.95]).unstack()
    if numeric:
        x = np.asarray(st.index, dtype=float)
        line, = ax.plot(x, st[0.5], "o-", label=label, lw=1.3, ms=3)
        ax.fill_between(x, st[0.05], st[0.95], color=line.get_color(), alpha=0.15, lw=0)
        return
    x = np.array([pos[v] for v in st.index], float) + dodge
    mid = st[0.5].to_numpy()
    ax.errorbar(x, mid, yerr=[mid - st[0.05].to_numpy(), st[0.95].to_numpy() - mid], fmt="o", ms=4, lw=1,
                capsize=3, label=label)


def plot_results(df: Any, spec: Spec, out: Path) -> list[Path]:
    """One PNG per swept parameter (:func:`plot_axis`), ``<figure>-vs-<parameter>.png``."""
    import matplotlib.pyplot as plt

    files: list[Path] = []
    if spec.figure not in df.columns or df[spec.figure].notna().sum() == 0:
        return files
    for axis in spec.axes:
        fig = plot_axis(df, spec, axis)
        path = out / f"{spec.figure}-vs-{axis}.png"

        def save(p: Path, fig: Any = fig) -> None:
            fig.savefig(p, dpi=100)
        with _named(path):
            write_with(path, save)
        plt.close(fig)
        files.append(path)
    return files


def plot_axis(df: Any, spec: Spec, axis: str) -> Any:
    """``spec.figure`` against the swept parameter ``axis`` (a matplotlib Figure; the
    caller closes it): median and 5–95 % band over the replicates (``spec.over``), a
    line over a numeric axis, markers and bars over categories. With two or more other
    swept parameters, one panel per value of the first (up to 9) and one line per
    combination of the rest (up to 10); a randomly drawn parameter is shown as a
    scatter of every run. Axes labelled with their units (:func:`unit_of`)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig_col = spec.figure
    ok = df[df[fig_col].notna()]
    numeric = _is_num(ok[axis])
    others = [a for a in spec.axes if a != axis and a not in spec.random_axes]
    facet, lines = (others[0], others[1:]) if len(others) >= 2 else (None, others)
    panels = list(dict.fromkeys(ok[facet].tolist()))[:_MAX_PANELS] if facet else [None]
    ncol = min(3, len(panels))
    nrow = math.ceil(len(panels) / ncol)
    fig, axs = plt.subplots(nrow, ncol, figsize=(4.2 * ncol + 1.2, 3.3 * nrow + 0.6), sharey=True, squeeze=False)
    xs_all = list(dict.fromkeys(ok[axis].tolist()))
    pos = {x: i for i, x in enumerate(xs_all)}
    for k, panel in enumerate(panels):
        ax = axs[k // ncol][k % ncol]
        sub = ok if facet is None else ok[ok[facet] == panel]
        if axis in spec.random_axes:
            ax.scatter(sub[axis], sub[fig_col], s=8, alpha=0.6)
        else:
            _bands(ax, sub, axis, fig_col, numeric, pos, lines)
            if not numeric:
                ax.set_xticks(range(len(xs_all)), [str(v) for v in xs_all], rotation=30, ha="right", fontsize=7)
        if (ok[fig_col] > 0).all():
            ax.set_yscale("log")
        if numeric and (ok[axis] > 0).all() and ok[axis].max() / ok[axis].min() >= 10:
            ax.set_xscale("log")
        if facet is not None:
            ax.set_title(f"{facet}={panel}", fontsize=8)
        ax.set_xlabel(_labelled(spec, axis), fontsize=8)
        if k % ncol == 0:
            ax.set_ylabel(_labelled(spec, fig_col), fontsize=8)
        ax.grid(True, which="both", alpha=0.3)
        ax.tick_params(labelsize=7)
    for k in range(len(panels), nrow * ncol):
        axs[k // ncol][k % ncol].set_visible(False)
    handles, labels = axs[0][0].get_legend_handles_labels()
    if len(handles) > 1:
        fig.legend(handles, labels, fontsize=7, loc="center right")
        fig.tight_layout(rect=(0, 0, 0.80, 0.95))
    else:
        fig.tight_layout(rect=(0, 0, 1, 0.95))
    reps = ", ".join(spec.over)
    fig.suptitle(f"{spec.name}: {fig_col} vs {axis} (median, 5–95 % over {reps})", fontsize=9)
    return fig


def _bands(ax: Any, sub: Any, axis: str, fig_col: str, numeric: bool, pos: dict[Any, int],
           lines: list[str]) -> None:
    """One :func:`_band` per combination of the ``lines`` parameters (up to 10)."""
    groups = list(sub.groupby(lines, sort=False, dropna=False))[:_MAX_LINES] if lines else [((), sub)]
    for i, (label, part) in enumerate(groups):
        vals = label if isinstance(label, tuple) else (label,)
        dodge = 0.0 if numeric else (i - (len(groups) - 1) / 2) * min(0.15, 0.6 / len(groups))
        _band(ax, part, axis, fig_col, numeric, pos, ", ".join(f"{o}={v}" for o, v in zip(lines, vals)) or fig_col,
              dodge)


# ---------------------------------------------------------------------------
# the API
# ---------------------------------------------------------------------------

def sweep(spec: Spec | str | os.PathLike[str] | Mapping[str, Any], client: Any = None, *,
          out: str | os.PathLike[str] | None = None, workers: int | None = None,
          progress: bool | Callable[[int, int], None] = False, retry_failed: bool = False,
          plots: bool = True) -> Any:
    """Run a sweep; return its table (pandas.DataFrame, one row per run).

    ``spec``: a :class:`Spec`, a TOML file's path or the parsed document.
    ``client``: None for a local cluster of ``workers`` processes (default:
    one per CPU), a ``distributed.Client``, a scheduler address
    (``"tcp://host:8786"``), or ``"serial"`` (every run in this process, no
    Dask). ``out``: the output folder (default ``results/sweep-<name>``);
    finished runs are journaled there, and a sweep started again with the
    same folder runs only the runs it has no record of (``retry_failed``:
    also those recorded with an error). Writes ``runs.csv``, ``summary.csv``,
    ``spec.toml`` and, with ``plots``, one PNG per swept parameter.
    ``progress``: True for a bar on stderr, or ``fn(done, total)``.

    ``df.attrs`` holds ``executed`` (runs run now), ``reused`` (taken from
    the journal), ``failed``, ``out``, ``engine`` and ``plots`` (the PNG files).
    """
    _need("pandas")
    sp = spec if isinstance(spec, Spec) else load_spec(spec)
    folder = Path(out) if out is not None else Path("results") / f"sweep-{sp.name}"
    folder.mkdir(parents=True, exist_ok=True)
    lock = _Lock(folder)
    try:
        if sp.text:
            text = sp.text

            def put(p: Path) -> None:
                p.write_text(text)
            with _named(folder / "spec.toml"):
                write_with(folder / "spec.toml", put)
        return _sweep_locked(sp, folder, client, workers, progress, retry_failed, plots)
    finally:
        lock.release()


def _sweep_locked(sp: Spec, folder: Path, client: Any, workers: int | None,
                  progress: bool | Callable[[int, int], None], retry_failed: bool, plots: bool) -> Any:
    jpath = folder / JOURNAL
    records = read_journal(jpath, repair=True)
    want = {r.key for r in sp.runs}
    if retry_failed:
        records = {k: v for k, v in records.items() if not v.get("error")}
    todo = [r for r in sp.runs if r.key not in records]
    reused = len(want) - len(todo)

    bar: Any = None
    if progress is True:
        from tqdm import tqdm

        bar = tqdm(total=len(sp.runs), initial=reused, desc=f"sweep {sp.name}", unit="run", file=sys.stderr,
                   dynamic_ncols=True, mininterval=0.5)
        report: Callable[[int], None] = bar.update
    elif callable(progress):
        count = [reused]

        def report(n: int) -> None:
            count[0] += n
            progress(count[0], len(sp.runs))  # type: ignore[operator]
    else:
        def report(n: int) -> None:
            return None

    executed = 0
    engine = "nothing to run"
    if todo:
        c, close, engine = _engine(client, workers)
        journal = _Journal(jpath)
        try:
            executed = _execute(sp, todo, c, journal, report)
        finally:
            journal.close()
            close()
            if bar is not None:
                bar.close()
        records = read_journal(jpath)  # later lines win: a retried run replaces its failed record
    elif bar is not None:
        bar.close()

    df = results_table(sp, records)
    with _named(folder / "runs.csv"):
        write_with(folder / "runs.csv", lambda p: df.to_csv(p, index=False))
    summ = summarize(df, sp)
    with _named(folder / "summary.csv"):
        write_with(folder / "summary.csv", lambda p: summ.to_csv(p, index=False))
    files = plot_results(df, sp, folder) if plots else []
    df.attrs.update(plots=[str(f) for f in files])
    df.attrs.update(executed=executed, reused=reused, failed=int((df["error"] != "").sum()), out=str(folder),
                    engine=engine)
    return df
