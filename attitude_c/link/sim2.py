"""Link v2 end to end in simulated line time (see docs/link.md, "Link v2").

:func:`simulate_link2` pushes numbered records through sender A -> the seeded
channel model (:class:`~attitude_c.link.sim.ChannelConfig`, both directions,
full duplex) -> receiver B -> a consumer queue, and checks every delivered
record against the one that should come next (in order, exactly once,
unaltered). ``engine="c"`` runs all of it in C (``csrc/host/link2_sim.c``,
millions of records per minute); ``engine="python"`` runs the same loop in
Python over any pair of ends (C or the spec-written Python ones) and can log
every byte each end handed out.
"""

from __future__ import annotations

from typing import Literal, Union

from .._lib import ffi_lib
from ..errors import InvalidArgument
from ..names import raise_for_status
from .sim import Channel, ChannelConfig
from .v2 import RECORD, Receiver2, Result2, Sender2
from .v2c import CReceiver2, CSender2, Link2Run

Impl = Literal["c", "python"]
AnySender = Union[Sender2, CSender2]
AnyReceiver = Union[Receiver2, CReceiver2]


def record(i: int, report_every: int = 0) -> bytes:
    """Record number i pushed into A by the simulation's producer (a sample whose codes hash i,
    or every report_every-th an OVERRUN-shaped report): the C generator's bytes."""
    ffi, lib = ffi_lib("f64")
    buf = ffi.new("uint8_t[6]")
    lib.att_link2_sim_record(i, report_every, buf)
    return bytes(buf)


def _ticks(name: str, seconds: float, baud: int) -> int:
    t = round(seconds * baud)
    if seconds < 0 or t < 0:
        raise InvalidArgument(f"{name} must be >= 0, got {seconds}")
    return t


def simulate_link2(n_records: int, channel: ChannelConfig | None = None, *, baud: int = 9600,
                   rto_ms: float = 62.5, max_samples: int = 16, ring_size: int = 32, report_every: int = 0,
                   period_s: float = 0.0, queue: int = 0, consume_period_s: float = 0.0,
                   reboot_sender_s: float = 0.0, reboot_receiver_s: float = 0.0, max_time_s: float = 0.0,
                   engine: Literal["c", "python"] = "c", sender: Impl = "c", receiver: Impl = "c",
                   log: list[tuple[int, int, int]] | None = None) -> Link2Run:
    """Simulate link v2; one tick = one bit time, a byte occupies its direction for 10 ticks.

    ``period_s`` 0: the producer offers a record whenever A's ring has room (throughput);
    ``queue`` 0: B always has room, else a consumer queue of that many records drained one
    per ``consume_period_s``. ``log`` (python engine): gets (tick, direction, byte) of every
    byte each end hands out (direction 0 = A->B). Reboots at 0 s mean none.
    """
    if isinstance(n_records, bool) or not isinstance(n_records, int) or n_records < 0:
        raise InvalidArgument(f"n_records must be an int >= 0, got {n_records!r}")
    chan_cfg = channel or ChannelConfig()
    rto = _ticks("rto_ms", rto_ms / 1000.0, baud)
    if not 1 <= rto <= 32767:
        raise InvalidArgument(f"rto_ms must give 1..32767 bit times at {baud} baud, got {rto_ms}")
    timing = {"period": _ticks("period_s", period_s, baud), "consume": _ticks("consume_period_s", consume_period_s, baud),
                  "rs": _ticks("reboot_sender_s", reboot_sender_s, baud),
                  "rr": _ticks("reboot_receiver_s", reboot_receiver_s, baud),
                  "max": _ticks("max_time_s", max_time_s, baud)}
    if engine == "c":
        if sender != "c" or receiver != "c" or log is not None:
            raise InvalidArgument('engine="c" runs the C ends only and keeps no log; use engine="python"')
        return _run_c(n_records, chan_cfg, baud, rto, max_samples, ring_size, report_every, queue, timing)
    if engine != "python":
        raise InvalidArgument(f'engine must be "c" or "python", got {engine!r}')
    a: AnySender = (CSender2 if sender == "c" else Sender2)(ring_size, max_samples, rto)
    b: AnyReceiver = (CReceiver2 if receiver == "c" else Receiver2)()
    return _run_py(a, b, n_records, Channel(chan_cfg, baud), baud, report_every, queue, timing, log)


def _run_c(n: int, chan_cfg: ChannelConfig, baud: int, rto: int, max_samples: int, ring_size: int,
           report_every: int, queue: int, timing: dict[str, int]) -> Link2Run:
    ffi, lib = ffi_lib("f64")
    ch = ffi.new("att_link_channel *")
    raise_for_status(lib.att_link_channel_init(ch, chan_cfg._c_config(ffi, baud)), "ChannelConfig")
    cfg = ffi.new("att_link2_sim_config *")
    lib.att_link2_sender_config_init(ffi.addressof(cfg, "sender"), ring_size)
    cfg.sender.rto, cfg.sender.max_samples = rto, max_samples
    cfg.ticks_per_byte = 10
    cfg.n_records, cfg.period, cfg.report_every = n, timing["period"], report_every
    cfg.queue, cfg.consume_period = queue, timing["consume"]
    cfg.reboot_sender_tick, cfg.reboot_receiver_tick, cfg.max_ticks = timing["rs"], timing["rr"], timing["max"]
    res = ffi.new("att_link2_sim_result *")
    raise_for_status(lib.att_link2_sim_run(cfg, ch, res), "att_link2_sim_run")
    names = ("bytes", "bit_flips", "corrupted", "dropped", "dead", "inserted", "duplicated")
    chan = {d: {k: int(getattr(ch.stats[i], k)) for k in names} for i, d in ((0, "a_to_b"), (1, "b_to_a"))}
    sender = {k: int(getattr(res, "s_" + k)) for k in ("frames", "records", "resent", "acks", "bad_frames",
                                                         "timeouts", "gobacks", "syns")}
    receiver = {k: int(getattr(res.receiver, k)) for k in ("frames", "bad_frames", "records", "duplicates", "gaps",
                                                           "refused", "syns", "no_session", "acks",
                                                           "bytes_discarded")}
    return Link2Run(int(res.offered), int(res.delivered), int(res.in_order), int(res.corrupt),
                    int(res.duplicates), int(res.lost), int(res.acked), int(res.unacked_end),
                    int(res.ticks) / baud, sender, receiver, chan)


class _Checker:
    def __init__(self, report_every: int) -> None:
        self.report_every = report_every
        self.expect = 0
        self.delivered = self.in_order = self.corrupt = self.duplicates = self.lost = 0

    def __call__(self, got: bytes) -> None:
        self.delivered += 1
        if got == record(self.expect, self.report_every):
            self.in_order += 1
            self.expect += 1
            return
        for d in range(1, min(256, self.expect) + 1):
            if got == record(self.expect - d, self.report_every):
                self.duplicates += 1
                return
        for d in range(1, 257):
            if got == record(self.expect + d, self.report_every):
                self.lost += d
                self.expect += d + 1
                return
        self.corrupt += 1


def _run_py(a: AnySender, b: AnyReceiver, n: int, ch: Channel, baud: int, report_every: int, queue: int,
            timing: dict[str, int], log: list[tuple[int, int, int]] | None) -> Link2Run:
    """The loop of csrc/host/link2_sim.c, step for step, over any pair of ends."""
    step = 10
    t = next_offer = next_consume = queued = offered = pushed = acked = 0
    a_base = 0
    to_b: list[int] = []
    to_a: list[int] = []
    check = _Checker(report_every)
    b.set_room(min(queue, 0xFFFF) if queue else 0xFFFF)
    while True:
        for x in to_b:
            if b.sink(x) == Result2.DELIVERED:
                for rec in b.delivered:
                    check(rec)
                queued += len(b.delivered)
        to_b = []
        for x in to_a:
            a.sink(x, t & 0xFFFF)
            base = a.base
            if base != a_base:
                acked += (base - a_base) & 0xFF
                a_base = base
        to_a = []
        if timing["rs"] and timing["rs"] <= t < timing["rs"] + step:
            a.reset()
            a_base = 0
        if timing["rr"] and timing["rr"] <= t < timing["rr"] + step:
            b.reset()
        if queue:
            if not timing["consume"]:
                queued = 0
            else:
                if queued == 0 or next_consume + timing["consume"] < t:
                    next_consume = next_consume if queued else t + timing["consume"]
                while queued and t >= next_consume:
                    queued -= 1
                    next_consume += timing["consume"]
            b.set_room(queue - queued)
        else:
            b.set_room(0xFFFF)
        while offered < n and t >= next_offer:
            if a.room > 0:
                a.push(record(pushed, report_every))
                pushed += 1
            elif not timing["period"]:
                break
            offered += 1
            next_offer = next_offer + timing["period"] if timing["period"] else t
        while True:
            r, byte = a.poll(t & 0xFFFF)
            if r != Result2.TIMEOUT:
                break
        if r == Result2.SEND and byte is not None:
            if log is not None:
                log.append((t, 0, byte))
            to_b.extend(ch.transmit(0, byte, t))
        r, byte = b.poll(t)
        if r == Result2.SEND and byte is not None:
            if log is not None:
                log.append((t, 1, byte))
            to_a.extend(ch.transmit(1, byte, t))
        t += step
        if timing["max"] and t >= timing["max"]:
            break
        if not timing["max"] and offered >= n and a.pending == 0 and not to_a and not to_b:
            break
    return Link2Run(pushed, check.delivered, check.in_order, check.corrupt, check.duplicates, check.lost, acked,
                    a.pending, t / baud, a.stats.as_dict(), b.stats.as_dict(), ch.stats())


__all__ = ["RECORD", "Link2Run", "record", "simulate_link2"]
