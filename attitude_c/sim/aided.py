"""The aided board in simulation (``SimConfig(board_kind="aided9")``, docs/simulation.md).

The AT89S52 board of docs/firmware.md ("The aided board") as the simulator
models it, stage by stage:

    motion → gyros, accelerometer and magnetometer front ends (:mod:`.frontend`)
    → TLC2543 codes of nine channels → the aided firmware's groups (BOOT,
    OVERSAMPLE, CHANNELS; per sample a gyro record, an accelerometer record when
    n % acc_every == 0, a magnetometer record when n % mag_every == 0)
    → link v2 (the C sender A, the channel simulator, the C receiver B, in
    simulated line time) → the block decoder and sequence tracker (``part``)
    → codes → SI with ``att_sensor`` (the nominal config of the same front-end
    figures: :func:`nominal_configs`) → the attitude filter, with no
    accelerometer or magnetometer on the samples without them (attitude-rx's
    NULL).

The plan's figures (:class:`AidedPlan`'s defaults) are those of the firmware's
default aided build, ``toolchain.firmware.AIDED`` (docs/firmware.md): this
package imports nothing outside itself, so they are repeated here, in this
one place; tests/test_sim_aided.py checks they agree.

A group is sent whole or not at all: when A's ring has no room for it the
sample is lost and an OVERRUN report takes its place at the next room, as the
firmware does.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, Literal

import numpy as np

from ..errors import InvalidArgument
from ..link import block
from ..link.sim import Channel, ChannelConfig
from ..link.v2 import Result2
from ..link.v2c import CReceiver2, CSender2
from ..sensorcal import SensorConfig
from .accelmag import SensorErrors, filtered
from .frontend import (
    ACCEL_FRONTENDS,
    FLIP_ZERO,
    MAG_FRONTENDS,
    AmrErrors,
    AmrMagnetometer,
    RatiometricAccel,
    flip_code,
    tlc2543_codes,
)
from .host import AuxStream, Calibration, Decoded

__all__ = ["AidedPlan", "BoardKind", "HostConfig", "aided_decode", "aided_records", "calibrated_configs", "carry_v2",
           "nominal_configs"]

BoardKind = Literal["gyro3", "aided9"]
HostConfig = Literal["nominal", "calibrated"]
#: the block format's group parts, in their order within a sample
PARTS: tuple[block.Channel, ...] = ("gyr", "acc", "mag")


@dataclass(frozen=True)
class AidedPlan:
    """The aided board: sampling plan, link v2 and front ends.

    ``acc_every`` / ``mag_every``: an accelerometer / magnetometer record in
    sample n when n % every == 0 (1..255, the CHANNELS report); ``baud``,
    ``ring`` (records A keeps until acknowledged), ``frame_records`` (records
    per frame), ``rto_s`` (A's go-back timeout; the firmware's batching of frames,
    ATT_LINK2_ONE_BATCH/HOLD, is not modeled: the host's C sender frames at once);
    ``mag_sr`` the magnetometer's set/reset (the firmware's ``FW_MAG_SR``: the code
    ``(c_set + 4095 − c_reset) // 2``, offsets cancelled; off: one conversion, the
    bridge and amplifier offsets in the code); ``host_config`` the host's acc-*/mag-*
    conversion: ``"calibrated"`` (the default: the exact inverse of this run's drawn part
    errors, what a perfect ``attitude calibrate`` would write — the procedure leaves 0.2 mg
    and 0.04 µT on simulated boards, docs/sensor.md — as a deployed board is calibrated
    before use) or ``"nominal"`` (the parts' typical figures, :func:`nominal_configs`: an
    uncalibrated board); ``period_s`` the BOOT period
    the firmware is built with (the CLI's default period for this board);
    ``accel`` / ``mag``: the front-end presets (:data:`.frontend.ACCEL_FRONTENDS`,
    :data:`.frontend.MAG_FRONTENDS`)."""

    acc_every: int = 1
    mag_every: int = 1
    period_s: float = 72 / 3600  # 72 ticks of 1/3600 s: 20 ms
    baud: int = 115200
    ring: int = 16
    frame_records: int = 16
    rto_s: float = 720 / 3600  # 720 ticks: 200 ms
    mag_sr: bool = False
    host_config: HostConfig = "calibrated"
    accel: str = "adxl335"
    mag: str = "hmc1043-ad623"

    def check(self) -> None:
        for name in ("acc_every", "mag_every"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or not 1 <= v <= 255:
                raise InvalidArgument(f"{name} must be an integer 1..255 (the CHANNELS report), got {v!r}")
        if self.accel not in ACCEL_FRONTENDS:
            raise InvalidArgument(f"accel front end must be one of {tuple(ACCEL_FRONTENDS)}, got {self.accel!r}")
        if self.host_config not in ("nominal", "calibrated"):
            raise InvalidArgument(f"host_config must be 'nominal' or 'calibrated', got {self.host_config!r}")
        if self.mag not in MAG_FRONTENDS:
            raise InvalidArgument(f"mag front end must be one of {tuple(MAG_FRONTENDS)}, got {self.mag!r}")

    @property
    def accel_part(self) -> RatiometricAccel:
        return ACCEL_FRONTENDS[self.accel]

    @property
    def mag_part(self) -> AmrMagnetometer:
        return MAG_FRONTENDS[self.mag]

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def nominal_configs(plan: AidedPlan) -> dict[str, SensorConfig]:
    """attitude-rx's nominal acc-*/mag-* conversion of the plan's front ends: zero the
    mid-scale code (ratiometric Vs/2; the set/reset code's 2047.5), scale the part's
    nominal units per code, axes as wired, no correction."""
    a, m = plan.accel_part, plan.mag_part
    mid = 2048.0  # Vs/2 of a REF+ = Vs converter: code 4096/2
    return {"accel": SensorConfig("acc", np.full(3, mid), np.full(3, a.units_per_code)),
            "mag": SensorConfig("mag", np.full(3, FLIP_ZERO if plan.mag_sr else mid), np.full(3, m.units_per_code))}


def calibrated_configs(plan: AidedPlan, acc_err: SensorErrors, mag_err: AmrErrors) -> dict[str, SensorConfig]:
    """The conversion that undoes the drawn errors exactly: zero the code of a zero
    input (the zero-g error, a fraction of Vs; the bridge and amplifier offsets
    through the gain, unless set/reset cancels them), M the inverse of the part's
    diag(1 + s)·C, no bias."""
    nom = nominal_configs(plan)
    full = 4096.0
    m = plan.mag_part
    acc_zero = nom["accel"].zero + full * acc_err.bias
    mag_zero = nom["mag"].zero + (0.0 if plan.mag_sr else
                                  full * m.gain * (mag_err.bridge.bias + mag_err.amp_offset_v / m.supply_v))
    return {"accel": SensorConfig("acc", acc_zero, nom["accel"].scale, matrix=np.linalg.inv(acc_err.matrix)),
            "mag": SensorConfig("mag", mag_zero, nom["mag"].scale, matrix=np.linalg.inv(mag_err.bridge.matrix))}


# ---------------------------------------------------------------------------
# front ends → codes
# ---------------------------------------------------------------------------

def frontend_words(cfg: Any, n: int, rngs: dict[str, np.random.Generator], instants: np.ndarray,
                   m: int) -> tuple[dict[str, AuxStream], dict[str, SensorConfig]]:
    """The accelerometer's and the magnetometer's per-sample sums of ``m`` TLC2543
    codes (n, 3) at the board's ``instants`` (n·m,), as AuxStreams holding the
    exact period-mean truth (values: the words, converted later), and the host's
    conversion of them (``plan.host_config``)."""
    plan: AidedPlan = cfg.aided
    traj, env, h = cfg.trajectory, cfg.environment, cfg.period
    full = cfg.sensors == "full"
    backend: Literal["tlc2543", "ideal"] = "ideal" if cfg.adc.backend == "ideal" else "tlc2543"
    acc = plan.accel_part
    acc_err = acc.draw_errors(rngs["afe_errors"])  # drawn even when switched off: same streams
    mag = plan.mag_part
    mag_err = mag.draw_errors(rngs["afe_errors"])
    if not full:
        acc, acc_err = acc.without_errors(), SensorErrors.none()
        mag, mag_err = mag.without_errors(), AmrErrors(SensorErrors.none(), np.zeros(3))
    f = filtered(lambda t: traj.specific_force(t, env), instants, acc.tau)
    acc_codes = tlc2543_codes(acc.volts(f, acc_err, h / m, rngs["afe_noise"]), acc.supply_v, backend)
    b = filtered(lambda t: traj.mag_field(t, env), instants, mag.tau)
    c_set, c_reset = mag.set_reset_codes(b, mag_err, h / m, rngs["afe_noise"], backend)
    t0 = traj.t_start
    out = {}
    for name, codes, truth_fn, unit in (
            ("accel", acc_codes, lambda t: traj.specific_force(t, env), "m/s^2"),
            ("mag", flip_code(c_set, c_reset) if plan.mag_sr else c_set, lambda t: traj.mag_field(t, env), "uT")):
        words = np.asarray(codes, dtype=np.int64).reshape(n, m, 3).sum(axis=1)
        truth = traj.period_means(truth_fn, t0, h, n)
        part = plan.accel if name == "accel" else plan.mag
        out[name] = AuxStream(name, part, unit, words.astype(float), truth, np.zeros((n, 3)),
                              np.zeros(n, dtype=bool))
    configs = nominal_configs(plan) if plan.host_config == "nominal" else calibrated_configs(plan, acc_err, mag_err)
    return out, configs


# ---------------------------------------------------------------------------
# the firmware's records
# ---------------------------------------------------------------------------

def aided_records(gyro: np.ndarray, acc: np.ndarray, mag: np.ndarray, plan: AidedPlan, m: int,
                  period: float) -> tuple[list[bytes], list[list[bytes]]]:
    """(header, groups): BOOT (link v2), OVERSAMPLE when m > 1, CHANNELS; then per
    sample its group of records (a sum the format cannot carry: one ADC_ERROR
    report in the group's place, as the firmware does)."""
    f = block.fmt()
    ticks = min(max(1, round(period * f.tick_hz)), f.period_max)
    head = [block.encode_boot(ticks, plan.baud, link="v2")]
    if m > 1:
        head.append(block.encode_oversample(m))
    head.append(block.encode_channels("aided9", PARTS, plan.acc_every, plan.mag_every))
    limit = block.sum_limit(m)
    groups = []
    for k in range(len(gyro)):
        rows = [gyro[k]]
        if k % plan.acc_every == 0:
            rows.append(acc[k])
        if k % plan.mag_every == 0:
            rows.append(mag[k])
        if all(0 <= r.min() and r.max() <= limit for r in rows):
            groups.append([block.encode_sums([int(x) for x in r], m) for r in rows])
        else:
            groups.append([block.encode_adc_error(k & 0xFFFF, 1)])
    return head, groups


# ---------------------------------------------------------------------------
# link v2 in simulated line time
# ---------------------------------------------------------------------------

class _Board:
    """The firmware's producer side: pushes group k into A whole, or loses it and owes an
    OVERRUN report that goes in first at the next room."""

    def __init__(self, a: CSender2, head: list[bytes]) -> None:
        self.a = a
        self.pushed: list[bytes] = []
        self.lost_first = self.lost = self.overruns = 0
        for r in head:
            self._push(r)

    def _push(self, rec: bytes) -> None:
        self.a.push(rec)
        self.pushed.append(rec)

    def offer(self, k: int, group: list[bytes]) -> None:
        if self.a.room < len(group) + (1 if self.lost else 0):
            self.lost_first = self.lost_first if self.lost else k
            self.lost += 1
            self.overruns += 1
            return
        if self.lost:
            self._push(block.encode_loss("overrun", self.lost_first & 0xFFFF, self.lost))
            self.lost = 0
        for r in group:
            self._push(r)


def carry_v2(head: list[bytes], groups: list[list[bytes]], plan: AidedPlan, period: float, ber: float,
             seed: int) -> tuple[list[bytes], dict[str, Any]]:
    """The records through A → channel (``ber`` both ways) → B at ``plan.baud``, one
    byte time per step; group k is offered at k·period (the header first).
    Returns (the records B delivered, in order; stats)."""
    step, bit = 10, plan.baud  # ticks are bit times; a byte takes ten
    a = CSender2(plan.ring, plan.frame_records, max(1, round(plan.rto_s * bit)))
    b = CReceiver2()
    b.set_room(0xFFFF)
    ch = Channel(ChannelConfig(ber=ber, seed=seed), bit)
    board = _Board(a, head)
    got: list[bytes] = []
    to_a: list[int] = []
    to_b: list[int] = []
    per = period * bit
    k = t = 0
    t_end = (len(groups) * period + 30.0) * bit  # the link drains within 30 s or gives up
    while t < t_end:
        for x in to_b:
            if b.sink(x) == Result2.DELIVERED:
                got.extend(b.delivered)
        for x in to_a:
            a.sink(x, t)
        while k < len(groups) and t >= k * per:
            board.offer(k, groups[k])
            k += 1
        r1, byte1 = a.poll(t)
        r2, byte2 = b.poll(t)
        to_b = list(ch.transmit(0, byte1, t)) if r1 == Result2.SEND and byte1 is not None else []
        to_a = list(ch.transmit(1, byte2, t)) if r2 == Result2.SEND and byte2 is not None else []
        idle = a.pending == 0 and not to_a and not to_b and r1 != Result2.SEND and r2 != Result2.SEND
        if idle and k >= len(groups):
            break
        # nothing on the line: on to the next group (at most 60000 ticks: A's 16-bit clock)
        t = max(t + step, min(math.ceil(k * per / step) * step, t + 60000)) if idle else t + step
    pushed = board.pushed
    stats = {"link": "v2", "ber": ber, "baud": bit, "seed": seed, "records_pushed": len(pushed),
             "records_delivered": len(got),
             "records_in_order": sum(1 for j, r in enumerate(got) if j < len(pushed) and r == pushed[j]),
             "records_unacked_at_end": a.pending, "overrun_samples": board.overruns,
             "link_time_s": t / bit, "sender": a.stats.as_dict(), "receiver": b.stats.as_dict(),
             "channel": ch.stats(), "backend": "c (att_link2 sender and receiver, att_link channel)"}
    return got, stats


# ---------------------------------------------------------------------------
# the host: decoder → codes → SI
# ---------------------------------------------------------------------------

def aided_decode(records: list[bytes], calib: Calibration, configs: dict[str, SensorConfig],
                 period: float) -> tuple[Decoded, dict[str, int]]:
    """Number the delivered records (the tracker's ``part``) and convert: gyro words →
    increments (``calib``), accelerometer and magnetometer words → m/s², µT
    (``configs``), NaN rows where a sample has no such record. A sample reported
    lost is held (the last good gyro sample, no aiding), as attitude-rx does."""
    tr = block.SeqTracker()
    gyro: dict[int, tuple[int, tuple[int, int, int]]] = {}
    aid: dict[str, dict[int, tuple[int, tuple[int, int, int]]]] = {"acc": {}, "mag": {}}
    held: list[int] = []
    reports: list[str] = []
    count = {"gyr": 0, "acc": 0, "mag": 0}
    for raw in records:
        rec, span, st = tr.decode(raw)
        if rec is None or span is None:
            continue
        if rec.kind == "sample" and st == 0:
            count[span.part] += 1
            (gyro if span.part == "gyr" else aid[span.part])[span.first] = (tr.oversample, rec.codes)
            continue
        reports.append(rec.kind)
        if rec.is_loss:
            held.extend(range(span.first, span.first + span.count))
    numbers = sorted(set(gyro) | set(held))
    last: tuple[int, tuple[int, int, int]] | None = None
    rows, keep = [], []
    for k in numbers:
        if k in gyro:
            last = gyro[k]
        if last is not None:
            rows.append(last)
            keep.append(k)
    idx = np.array(keep, dtype=np.int64)
    words = np.array([r[1] for r in rows], dtype=np.int64).reshape(-1, 3)
    n_of = np.array([r[0] for r in rows], dtype=np.int64)
    inc = np.zeros((len(rows), 3))
    sensor = calib.sensor()
    for n in np.unique(n_of):
        inc[n_of == n] = sensor.increments(words[n_of == n], int(n), period)
    aux = {name: _convert(aid[part], idx, set(gyro), configs[name])
           for name, part in (("accel", "acc"), ("mag", "mag"))}
    held_set = [k for k in held if k in set(keep)]
    return Decoded(inc, idx, words, held_set, reports, aux), count


def _convert(got: dict[int, tuple[int, tuple[int, int, int]]], idx: np.ndarray, good: set[int],
             config: SensorConfig) -> np.ndarray:
    """One sensor's records ``got`` (sample → (n, words)) on the rows ``idx``: values
    (len(idx), 3), NaN where the sample has no record or was held (no good gyro record)."""
    vals = np.full((len(idx), 3), np.nan)
    js = [j for j, k in enumerate(idx) if int(k) in got and int(k) in good]
    for n in {got[int(idx[j])][0] for j in js}:  # one conversion per oversample factor
        sel = [j for j in js if got[int(idx[j])][0] == n]
        w = np.array([got[int(idx[j])][1] for j in sel], dtype=np.int64).reshape(-1, 3)
        vals[sel] = config.convert(w, n)
    return vals
