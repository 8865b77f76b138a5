"""The C link v2 machines (csrc/src/link2_sender.c, link2_receiver.c) behind
the same Python interface as :mod:`attitude_c.link.v2`, and the all-C
end-to-end simulation (csrc/host/link2_sim.c)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from .._lib import ffi_lib
from ..errors import InvalidArgument, LinkBusy
from ..names import raise_for_status
from .v2 import (
    DEFAULT_RTO_MS,
    RECORD,
    RING_MAX,
    SAMPLES_DEFAULT,
    SAMPLES_MAX,
    TIMEOUT_MAX,
    Receiver2Stats,
    Result2,
    Sender2Stats,
    _byte,
    _check_int,
)

_SENDER_FIELDS = ("frames", "records", "resent", "acks", "bad_frames", "timeouts", "gobacks", "syns")
_RECEIVER_FIELDS = ("frames", "bad_frames", "records", "duplicates", "gaps", "refused", "syns", "no_session",
                    "acks", "bytes_discarded")


def _result(code: int, what: str) -> Result2:
    if code < 0:
        raise_for_status(code, what)
    return Result2(code)


class CSender2:
    """Sender A of link v2: the C machine (``att_link2_sender``)."""

    def __init__(self, ring_size: int = RING_MAX, max_samples: int = SAMPLES_DEFAULT,
                 rto: int = DEFAULT_RTO_MS) -> None:
        _check_int("ring_size", ring_size, 1, RING_MAX)
        if ring_size & (ring_size - 1):
            raise InvalidArgument(f"ring_size must be a power of two, got {ring_size}")
        _check_int("max_samples", max_samples, 1, SAMPLES_MAX)
        _check_int("rto", rto, 1, TIMEOUT_MAX)
        self._ffi, self._lib = ffi_lib("f64")
        ffi, lib = self._ffi, self._lib
        self._s: Any = ffi.new("att_link2_sender *")
        self._ring: Any = ffi.new("uint8_t[]", ring_size * RECORD)
        self._rec: Any = ffi.new("uint8_t[6]")
        self._out: Any = ffi.new("uint8_t *")
        cfg = ffi.new("att_link2_sender_config *")
        lib.att_link2_sender_config_init(cfg, ring_size)
        cfg.max_samples, cfg.rto = max_samples, rto
        raise_for_status(lib.att_link2_sender_init(self._s, cfg, self._ring), "att_link2_sender_init")
        self.ring_size, self.max_samples, self.rto = ring_size, max_samples, rto

    def reset(self) -> None:
        self._lib.att_link2_sender_reset(self._s)

    @property
    def room(self) -> int:
        return int(self._lib.att_link2_sender_room(self._s))

    @property
    def pending(self) -> int:
        return int(self._lib.att_link2_sender_pending(self._s))

    def push(self, record: bytes) -> None:
        if not isinstance(record, (bytes, bytearray)) or len(record) != RECORD:
            raise InvalidArgument(f"record must be {RECORD} bytes, got {record!r}")
        self._ffi.memmove(self._rec, bytes(record), RECORD)
        st = self._lib.att_link2_sender_push(self._s, self._rec)
        if st == self._lib.ATT_LINK2_E_FULL:
            raise LinkBusy("link v2 sender ring full")
        raise_for_status(st, "att_link2_sender_push")

    def sink(self, byte: int, tick: int = 0) -> Result2:
        return _result(self._lib.att_link2_sender_sink(self._s, _byte("byte", byte), tick & 0xFFFF),
                       "att_link2_sender_sink")

    def poll(self, tick: int = 0) -> tuple[Result2, int | None]:
        r = _result(self._lib.att_link2_sender_poll(self._s, tick & 0xFFFF, self._out), "att_link2_sender_poll")
        return r, (int(self._out[0]) if r == Result2.SEND else None)

    def ticks_left(self, now: int) -> int:
        return int(self._lib.att_link2_sender_ticks_left(self._s, now & 0xFFFF))

    @property
    def base(self) -> int:
        return int(self._s.base)

    @property
    def stats(self) -> Sender2Stats:
        return Sender2Stats(**{f: int(getattr(self._s.stats, f)) for f in _SENDER_FIELDS})


class CReceiver2:
    """Receiver B of link v2: the C machine (``att_link2_receiver``)."""

    def __init__(self, room: int = 0) -> None:
        _check_int("room", room, 0, 0xFFFF)
        self._ffi, self._lib = ffi_lib("f64")
        ffi, lib = self._ffi, self._lib
        self._r: Any = ffi.new("att_link2_receiver *")
        self._obuf: Any = ffi.new("uint8_t[]", lib.ATT_LINK2_OUT_MAX)
        self._out: Any = ffi.new("uint8_t *")
        raise_for_status(lib.att_link2_receiver_init(self._r, self._obuf), "att_link2_receiver_init")
        lib.att_link2_receiver_set_room(self._r, room)
        self.delivered: list[bytes] = []

    def reset(self) -> None:
        self._lib.att_link2_receiver_reset(self._r)
        self.delivered = []

    @property
    def room(self) -> int:
        return int(self._r.room)

    @property
    def synced(self) -> bool:
        return bool(self._r.synced)

    @property
    def expected(self) -> int:
        return int(self._r.expected)

    def set_room(self, room: int) -> None:
        self._lib.att_link2_receiver_set_room(self._r, _check_int("room", room, 0, 0xFFFF))

    def sink(self, byte: int, tick: int = 0) -> Result2:
        r = _result(self._lib.att_link2_receiver_sink(self._r, _byte("byte", byte)), "att_link2_receiver_sink")
        n = int(self._r.n_out) if r == Result2.DELIVERED else 0
        raw = bytes(self._ffi.buffer(self._obuf, RECORD * n))
        self.delivered = [raw[RECORD * i:RECORD * (i + 1)] for i in range(n)]
        return r

    def poll(self, tick: int = 0) -> tuple[Result2, int | None]:
        r = _result(self._lib.att_link2_receiver_poll(self._r, self._out), "att_link2_receiver_poll")
        return r, (int(self._out[0]) if r == Result2.SEND else None)

    @property
    def stats(self) -> Receiver2Stats:
        return Receiver2Stats(**{f: int(getattr(self._r.stats, f)) for f in _RECEIVER_FIELDS})


@dataclass
class Link2Run:
    """Outcome of :func:`simulate_link2` (counts of records)."""

    offered: int
    delivered: int
    in_order: int
    corrupt: int
    duplicates: int
    lost: int
    acked: int
    unacked_end: int
    duration: float  # simulated seconds
    sender: dict[str, int]
    receiver: dict[str, int]
    channel: dict[str, dict[str, int]]

    @property
    def rate(self) -> float:
        """Records delivered per simulated second."""
        return self.delivered / self.duration if self.duration > 0 else 0.0

    def summary(self) -> dict[str, Any]:
        return {"offered": self.offered, "delivered": self.delivered, "in_order": self.in_order,
                "corrupt": self.corrupt, "duplicates": self.duplicates, "lost": self.lost,
                "acked": self.acked, "unacked_end": self.unacked_end, "duration_s": self.duration,
                "records_per_s": self.rate, "sender": self.sender, "receiver": self.receiver}
