"""Channel simulator and simulated-time runs of the link (docs/link.md).

Time is counted in bit times of the line (1/baud s); an 8N1 byte lasts 10
of them, and each direction of the line carries one byte at a time. The
channel model itself is C (csrc/host/link_sim.c, seeded splitmix64), so
runs with Python ends and the all-C fast path see the *same* faults for
the same seed and can be compared byte for byte.

Main entry point::

    run = simulate_link(blocks, channel=ChannelConfig(ber=1e-3, seed=1))
    run.accepted, run.accepted_index, run.gave_up, run.sender_stats, ...
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, Union

import numpy as np

from .._lib import ffi_lib
from ..errors import InvalidArgument, InvalidType
from ..names import raise_for_status
from .cends import Impl, make_receiver, make_sender
from .protocol import (
    BLOCK_MAX,
    DEFAULT_ANSWER_TIMEOUT_MS,
    DEFAULT_GAP_TIMEOUT_MS,
    DEFAULT_MAX_ATTEMPTS,
    DEFAULT_SYN_TIMEOUT_MS,
    TIMEOUT_MAX,
    Result,
)

BITS_PER_BYTE = 10  # 8N1: start + 8 data + stop

OUTCOME_PENDING = 0
OUTCOME_ACKED = 1
OUTCOME_GAVE_UP = 2
OUTCOME_LOST_REBOOT = 3

Rate = Union[float, tuple[float, float]]  # both directions, or (A->B, B->A)


def _rate(name: str, value: Rate) -> tuple[float, float]:
    pair = value if isinstance(value, tuple) else (value, value)
    if len(pair) != 2:
        raise InvalidArgument(f"{name} must be a probability or a pair (A->B, B->A)")
    out = []
    for v in pair:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise InvalidType(f"{name} must be a float, got {type(v).__name__}")
        if not (0.0 <= float(v) <= 1.0):  # also rejects NaN
            raise InvalidArgument(f"{name} must be a probability in [0, 1], got {v!r}")
        out.append(float(v))
    return out[0], out[1]


@dataclass
class ChannelConfig:
    """A bad line. Probabilities apply per byte (``ber``: per data bit);
    give one number for both directions or a pair ``(A->B, B->A)``.

    ``dead``: up to 4 windows ``(start_s, length_s)`` during which the line
    loses every byte in both directions. ``seed`` makes the run repeatable.
    """

    ber: Rate = 0.0
    drop: Rate = 0.0
    insert: Rate = 0.0
    duplicate: Rate = 0.0
    dead: Sequence[tuple[float, float]] = ()
    seed: int = 1

    def _c_config(self, ffi: Any, baud: int) -> Any:
        cfg = ffi.new("att_link_channel_config *")
        ber, drop, ins, dup = (_rate("ber", self.ber), _rate("drop", self.drop),
                               _rate("insert", self.insert), _rate("duplicate", self.duplicate))
        for d, side in ((0, cfg.a_to_b), (1, cfg.b_to_a)):
            side.ber, side.p_drop, side.p_insert, side.p_duplicate = ber[d], drop[d], ins[d], dup[d]
        if len(self.dead) > 4:
            raise InvalidArgument(f"dead: at most 4 windows, got {len(self.dead)}")
        for i, (start, length) in enumerate(self.dead):
            if not (math.isfinite(start) and math.isfinite(length)) or start < 0 or length < 0:
                raise InvalidArgument(f"dead[{i}] must be (start_s >= 0, length_s >= 0), got {(start, length)}")
            cfg.dead_start[i] = round(start * baud)
            cfg.dead_length[i] = round(length * baud)
        cfg.n_dead = len(self.dead)
        if isinstance(self.seed, bool) or not isinstance(self.seed, int):
            raise InvalidType(f"seed must be an int, got {type(self.seed).__name__}")
        cfg.seed = self.seed & 0xFFFFFFFFFFFFFFFF
        return cfg


class Channel:
    """The C channel model: ``transmit(direction, byte, tick) -> bytes``
    (direction 0 = A->B, 1 = B->A; tick in bit times)."""

    def __init__(self, config: ChannelConfig | None = None, baud: int = 9600) -> None:
        self.config = config or ChannelConfig()
        self._ffi, self._lib = ffi_lib("f64")
        self._ch: Any = self._ffi.new("att_link_channel *")
        raise_for_status(self._lib.att_link_channel_init(self._ch, self.config._c_config(self._ffi, baud)),
                         "ChannelConfig")
        self._out: Any = self._ffi.new("uint8_t[3]")

    def transmit(self, direction: int, byte: int, tick: int) -> bytes:
        n = self._lib.att_link_channel_transmit(self._ch, direction, byte, tick, self._out)
        raise_for_status(n, "Channel.transmit")
        return bytes(self._out[0:n])

    def stats(self) -> dict[str, dict[str, int]]:
        names = ("bytes", "bit_flips", "corrupted", "dropped", "dead", "inserted", "duplicated")
        return {d: {n: int(getattr(self._ch.stats[i], n)) for n in names}
                for i, d in ((0, "a_to_b"), (1, "b_to_a"))}


@dataclass
class LinkRun:
    """What happened to a list of blocks pushed from A to B."""

    blocks: np.ndarray  # (n, N) uint8: what A was given
    accepted: np.ndarray  # (m, N) uint8: every block B accepted, in order
    accepted_index: np.ndarray  # (m,) int64: index of the block A was sending (-1: none)
    accepted_time: np.ndarray  # (m,) float64: simulated seconds
    outcome: np.ndarray  # (n,) uint8: OUTCOME_* per block
    sender_stats: dict[str, int]
    receiver_stats: dict[str, int]
    channel_stats: dict[str, dict[str, int]]
    duration: float  # simulated seconds
    engine: str = "c"
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def gave_up(self) -> np.ndarray:
        """Indices of the blocks A gave up on."""
        return np.flatnonzero(self.outcome == OUTCOME_GAVE_UP)

    @property
    def lost_to_reboot(self) -> np.ndarray:
        return np.flatnonzero(self.outcome == OUTCOME_LOST_REBOOT)

    @property
    def correct(self) -> np.ndarray:
        """Mask over accepted blocks: equal to the block A was sending."""
        idx = self.accepted_index
        ok = idx >= 0
        out = np.zeros(len(idx), dtype=bool)
        out[ok] = np.all(self.accepted[ok] == self.blocks[idx[ok]], axis=1)
        return out

    @property
    def duplicate(self) -> np.ndarray:
        """Mask over accepted blocks: a correct copy of a block B had already accepted."""
        seen: set[int] = set()
        dup = np.zeros(len(self.accepted_index), dtype=bool)
        for m, (i, ok) in enumerate(zip(self.accepted_index.tolist(), self.correct.tolist())):
            if ok:
                if i in seen:
                    dup[m] = True
                seen.add(i)
        return dup

    def summary(self) -> dict[str, Any]:
        n = len(self.blocks)
        correct = self.correct
        dup = self.duplicate
        unique = int(np.count_nonzero(correct & ~dup))
        return {
            "blocks": n,
            "accepted_by_B": len(self.accepted),
            "delivered_unique": unique,
            # blocks of which no intact copy reached B (delivered_unique + lost == blocks);
            # not gave_up + lost_to_reboot: B may hold a block whose 0x00 answers were all lost
            "lost": n - unique,
            "undetected_errors": int(np.count_nonzero(~correct)),
            "duplicates": int(np.count_nonzero(dup)),
            "acked": int(np.count_nonzero(self.outcome == OUTCOME_ACKED)),
            "gave_up": len(self.gave_up),
            "lost_to_reboot": len(self.lost_to_reboot),
            "duration_s": self.duration,
            "blocks_per_s": unique / self.duration if self.duration > 0 else 0.0,
            "sender": dict(self.sender_stats),
            "receiver": dict(self.receiver_stats),
        }


def _ticks(name: str, ms: float, baud: int) -> int:
    if not math.isfinite(ms) or ms <= 0:
        raise InvalidArgument(f"{name} must be a positive number of ms, got {ms!r}")
    t = math.ceil(ms * baud / 1000.0)
    if t > TIMEOUT_MAX:
        raise InvalidArgument(f"{name} = {ms} ms is {t} bit times at {baud} baud; at most {TIMEOUT_MAX}")
    return t


def _as_blocks(blocks: Any, block_size: int | None) -> np.ndarray:
    if isinstance(blocks, (bytes, bytearray)):
        raise InvalidType("blocks must be a 2-D array or a list of blocks, not one bytes object")
    arr = np.asarray([bytes(b) for b in blocks] if isinstance(blocks, list) and blocks
                     and isinstance(blocks[0], (bytes, bytearray)) else blocks)
    if arr.dtype.kind == "S":
        arr = np.frombuffer(arr.tobytes(), dtype=np.uint8).reshape(len(arr), -1)
    if arr.ndim != 2:
        raise InvalidArgument(f"blocks must be 2-D (n_blocks, block_size), got shape {arr.shape}")
    if arr.dtype.kind not in "ui":
        raise InvalidType(f"blocks must hold integers 0..255, got dtype {arr.dtype}")
    if arr.size and (arr.min() < 0 or arr.max() > 255):
        raise InvalidArgument("blocks must hold byte values 0..255")
    if block_size is not None and arr.shape[1] != block_size:
        raise InvalidArgument(f"blocks have {arr.shape[1]} bytes each, block_size is {block_size}")
    if not 1 <= arr.shape[1] <= BLOCK_MAX:
        raise InvalidArgument(f"block size must be 1..{BLOCK_MAX}, got {arr.shape[1]}")
    return np.ascontiguousarray(arr, dtype=np.uint8)


def simulate_link(
    blocks: Any,
    *,
    channel: ChannelConfig | None = None,
    sender: Impl = "c",
    receiver: Impl = "c",
    baud: int = 9600,
    block_size: int | None = None,
    syn_timeout_ms: float = DEFAULT_SYN_TIMEOUT_MS,
    answer_timeout_ms: float = DEFAULT_ANSWER_TIMEOUT_MS,
    gap_timeout_ms: float = DEFAULT_GAP_TIMEOUT_MS,
    max_attempts: int = DEFAULT_MAX_ATTEMPTS,
    reboots: Iterable[tuple[float, Literal["sender", "receiver"]]] = (),
    max_time_s: float | None = None,
    engine: Impl | None = None,
) -> LinkRun:
    """Push ``blocks`` ((n, N) uint8, or a list of N-byte ``bytes``) through
    sender A -> :class:`ChannelConfig` line -> receiver B at ``baud`` 8N1.

    ``sender`` / ``receiver``: ``"c"`` or ``"python"``. ``engine``: ``"c"``
    (the fast all-C loop; needs both ends C, the default then) or
    ``"python"`` (a Python loop over the chosen ends, same semantics).
    ``reboots``: ``(time_s, "sender" | "receiver")`` -- that end loses its
    state (A also loses the block in progress and moves on).
    """
    arr = _as_blocks(blocks, block_size)
    _n_blocks, _n = arr.shape
    if isinstance(baud, bool) or not isinstance(baud, int) or not 50 <= baud <= 4_000_000:
        raise InvalidArgument(f"baud must be an int in 50..4000000, got {baud!r}")
    chan_cfg = channel or ChannelConfig()
    if engine is None:
        engine = "c" if (sender == "c" and receiver == "c") else "python"
    if engine not in ("c", "python"):
        raise InvalidArgument(f"engine must be 'c' or 'python', got {engine!r}")
    if engine == "c" and (sender != "c" or receiver != "c"):
        raise InvalidArgument("engine='c' runs the C ends only; use engine='python' for Python ends")
    for name, impl in (("sender", sender), ("receiver", receiver)):
        if impl not in ("c", "python"):
            raise InvalidArgument(f"{name} must be 'c' or 'python', got {impl!r}")
    timing = {
        "syn": _ticks("syn_timeout_ms", syn_timeout_ms, baud),
        "answer": _ticks("answer_timeout_ms", answer_timeout_ms, baud),
        "gap": _ticks("gap_timeout_ms", gap_timeout_ms, baud),
    }
    reb = []
    for time_s, who in reboots:
        if who not in ("sender", "receiver"):
            raise InvalidArgument(f"reboot side must be 'sender' or 'receiver', got {who!r}")
        if not math.isfinite(time_s) or time_s < 0:
            raise InvalidArgument(f"reboot time must be >= 0 s, got {time_s!r}")
        reb.append((round(time_s * baud), 0 if who == "sender" else 1))
    if len(reb) > 8:
        raise InvalidArgument(f"at most 8 reboots, got {len(reb)}")
    max_ticks = 0 if max_time_s is None else max(1, round(max_time_s * baud))
    if engine == "c":
        return _run_c(arr, chan_cfg, baud, timing, max_attempts, reb, max_ticks)
    return _run_py(arr, chan_cfg, baud, timing, max_attempts, reb, max_ticks, sender, receiver)


def _sender_dict(s: Any) -> dict[str, int]:
    d = {k: int(getattr(s, k)) for k in ("blocks_sent", "blocks_accepted", "naks", "timeouts",
                                         "gave_up", "bytes_discarded")}
    d["retries"] = d["naks"] + d["timeouts"] - d["gave_up"]
    return d


def _run_c(arr: np.ndarray, chan_cfg: ChannelConfig, baud: int, timing: dict[str, int],
           max_attempts: int, reb: list[tuple[int, int]], max_ticks: int) -> LinkRun:
    ffi, lib = ffi_lib("f64")
    n_blocks, n = arr.shape
    cfg = ffi.new("att_link_sim_config *")
    lib.att_link_sender_config_init(ffi.addressof(cfg, "sender"), n)
    cfg.sender.syn_timeout = timing["syn"]
    cfg.sender.answer_timeout = timing["answer"]
    if isinstance(max_attempts, bool) or not isinstance(max_attempts, int) or not 1 <= max_attempts <= 255:
        raise InvalidArgument(f"max_attempts must be an int in 1..255, got {max_attempts!r}")
    cfg.sender.max_attempts = max_attempts
    lib.att_link_receiver_config_init(ffi.addressof(cfg, "receiver"), n)
    cfg.receiver.gap_timeout = timing["gap"]
    cfg.ticks_per_byte = BITS_PER_BYTE
    for i, (t, who) in enumerate(reb):
        cfg.reboot_tick[i] = t
        cfg.reboot_who[i] = who
    cfg.n_reboots = len(reb)
    cfg.max_ticks = max_ticks
    cap = 2 * n_blocks + 64
    while True:
        acc = np.zeros((cap, n), dtype=np.uint8)
        acc_index = np.zeros(cap, dtype=np.int64)
        acc_tick = np.zeros(cap, dtype=np.uint64)
        outcome = np.zeros(n_blocks, dtype=np.uint8)
        res = ffi.new("att_link_sim_result *")
        # a fresh channel per attempt so a retry sees the same faults
        channel = Channel(chan_cfg, baud)
        rc = lib.att_link_sim_run(
            cfg, channel._ch, ffi.from_buffer("uint8_t[]", arr), n_blocks,
            ffi.from_buffer("uint8_t[]", acc), ffi.from_buffer("int64_t[]", acc_index),
            ffi.from_buffer("uint64_t[]", acc_tick), cap,
            ffi.from_buffer("uint8_t[]", outcome), res)
        raise_for_status(rc, "att_link_sim_run")
        if res.n_accepted <= cap:
            break
        cap = int(res.n_accepted) + 64
    m = int(res.n_accepted)
    sstats = {k: int(getattr(res, "s_" + k)) for k in ("blocks_sent", "blocks_accepted", "naks",
                                                         "timeouts", "gave_up", "bytes_discarded")}
    sstats["retries"] = sstats["naks"] + sstats["timeouts"] - sstats["gave_up"]
    rstats = {k: int(getattr(res.receiver, k)) for k in ("syns", "blocks_accepted", "naks",
                                                         "timeouts", "resyncs", "bytes_discarded")}
    return LinkRun(blocks=arr, accepted=acc[:m].copy(), accepted_index=acc_index[:m].copy(),
                   accepted_time=acc_tick[:m].astype(np.float64) / baud, outcome=outcome,
                   sender_stats=sstats, receiver_stats=rstats, channel_stats=channel.stats(),
                   duration=int(res.ticks) / baud, engine="c")


def _run_py(arr: np.ndarray, chan_cfg: ChannelConfig, baud: int, timing: dict[str, int],
            max_attempts: int, reb: list[tuple[int, int]], max_ticks: int,
            sender_impl: Impl, receiver_impl: Impl) -> LinkRun:
    """The same event loop as att_link_sim_run, in Python, over any ends."""
    n_blocks, n = arr.shape
    channel = Channel(chan_cfg, baud)
    a = make_sender(sender_impl, block_size=n, syn_timeout=timing["syn"],
                    answer_timeout=timing["answer"], max_attempts=max_attempts)
    b = make_receiver(receiver_impl, block_size=n, gap_timeout=timing["gap"])
    tpb = BITS_PER_BYTE
    rows = [bytes(r) for r in arr]
    la: list[tuple[int, int, int]] = []  # (arrival, byte, tag) A -> B
    lb: list[tuple[int, int]] = []  # (arrival, byte) B -> A
    busy_a = busy_b = 0
    t = 0
    k = 0
    cur = -1
    outcome = np.zeros(n_blocks, dtype=np.uint8)
    acc: list[bytes] = []
    acc_index: list[int] = []
    acc_tick: list[int] = []
    pending_reboots = sorted(enumerate(reb), key=lambda x: x[0])  # keep given order
    done = [False] * len(reb)
    while True:
        for i, (rt, who) in pending_reboots:
            if not done[i] and rt <= t:
                done[i] = True
                if who == 0:
                    if cur >= 0 and outcome[cur] == OUTCOME_PENDING:
                        outcome[cur] = OUTCOME_LOST_REBOOT
                    cur = -1
                    a.reset()
                else:
                    b.reset()
        while la and la[0][0] <= t:
            _, byte, tag = la.pop(0)
            if b.sink(byte, t) is Result.ACCEPTED:
                acc.append(b.block)
                acc_index.append(tag)
                acc_tick.append(t)
        while lb and lb[0][0] <= t:
            _, byte = lb.pop(0)
            if a.sink(byte, t) is Result.ACCEPTED and cur >= 0:
                outcome[cur] = OUTCOME_ACKED
                cur = -1
        if busy_a <= t:
            while True:
                r, out = a.poll(t)
                if r is Result.IDLE:
                    if k >= n_blocks:
                        break
                    a.start(rows[k], t)
                    cur = k
                    k += 1
                    continue
                if r is Result.SEND:
                    assert out is not None
                    for x in channel.transmit(0, out, t):
                        la.append((t + tpb, x, cur))
                    busy_a = t + tpb
                    break
                if r is Result.GAVE_UP:
                    if cur >= 0:
                        outcome[cur] = OUTCOME_GAVE_UP
                    cur = -1
                    continue
                if r is Result.NONE:
                    break
        if busy_b <= t:
            while True:
                r, out = b.poll(t)
                if r is Result.SEND:
                    assert out is not None
                    for x in channel.transmit(1, out, t):
                        lb.append((t + tpb, x))
                    busy_b = t + tpb
                    break
                if r in (Result.NONE, Result.IDLE):
                    break
        left_a = a.ticks_left(t)
        if (k >= n_blocks and cur < 0 and left_a is None and not la and not lb
                and busy_a <= t and busy_b <= t):
            break
        cands = []
        if la:
            cands.append(la[0][0])
        if lb:
            cands.append(lb[0][0])
        if busy_a > t:
            cands.append(busy_a)
        elif left_a is not None:
            cands.append(t + max(left_a, 1))
        if busy_b > t:
            cands.append(busy_b)
        else:
            left_b = b.ticks_left(t)
            if left_b is not None:
                cands.append(t + max(left_b, 1))
        for i, (rt, _who) in pending_reboots:
            if not done[i]:
                cands.append(rt if rt > t else t + 1)
        if not cands:
            break
        nxt = min(cands)
        if max_ticks and nxt > max_ticks:
            t = max_ticks
            break
        t = nxt
    sstats = a.stats.as_dict()
    rstats = b.stats.as_dict()
    return LinkRun(blocks=arr,
                   accepted=np.frombuffer(b"".join(acc), dtype=np.uint8).reshape(len(acc), n).copy(),
                   accepted_index=np.asarray(acc_index, dtype=np.int64),
                   accepted_time=np.asarray(acc_tick, dtype=np.float64) / baud,
                   outcome=outcome, sender_stats=sstats, receiver_stats=rstats,
                   channel_stats=channel.stats(), duration=t / baud, engine="python",
                   extra={"sender": sender_impl, "receiver": receiver_impl})
