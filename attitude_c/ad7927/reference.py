"""Pure-Python reference driver for the AD7927, written from the datasheet.

The second opinion on the C driver (csrc/src/ad7927.c): the same frames,
built from the datasheet's bit tables (control register Table 5, sequencer
Table 9, shadow register Table 10, serial interface Figure 26) with lists
of named fields and bits, and its own pipeline bookkeeping. It shares no
code with the C driver. It talks to the device at pin level (any object
with ``set_cs``, ``set_sclk``, ``set_din``, ``get_dout``, ``delay_ns``, such
as :class:`~attitude_c.ad7927.model.Ad7927Model`) or, with ``frames=True``,
at frame level (an object with ``transfer(words, hold_ns) -> words``).

``sample_after_fall=True`` is a deliberately broken variant: it reads DOUT
right after each SCLK falling edge, before the next bit is valid — the model
must catch it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol

from ..errors import DeviceError, InvalidArgument
from ._errors import AddressMismatch, FrameError

# Serial-interface timing the reference waits for (ns; datasheet t2..t12).
CS_TO_SCLK = 35   # t2 >= 10 ns to the first falling edge; t3 <= 35 ns until the leading zero is on DOUT
DIN_SETUP = 10    # t9: DIN before the falling edge that latches it
SCLK_LOW = 40     # t5 (>= 0.4 period); t4 <= 40 ns: the next DOUT bit is valid after this
SCLK_HIGH = 20    # t6 (the high phase also holds the DIN setup: 30 ns in all)
QUIET = 50        # t_QUIET: CS high between frames
POWER_UP = 1000   # t12: after the write that leaves full shutdown

# Power management (PM1 PM0), datasheet.
NORMAL, FULL_SHUTDOWN = 0b11, 0b10


class Pins(Protocol):
    def set_cs(self, level: int) -> None: ...
    def set_sclk(self, level: int) -> None: ...
    def set_din(self, level: int) -> None: ...
    def get_dout(self) -> int: ...
    def delay_ns(self, ns: int) -> None: ...


def control_word(*, seq: int = 0, add: int = 0, pm: int = NORMAL, shadow: int = 0,
                 range_bit: int = 0, coding: int = 1, write: int = 1) -> int:
    """The 16-bit DIN word of a control write: the 12 register bits (WRITE,
    SEQ, don't care, ADD2..0, PM1..0, SHADOW, don't care, RANGE, CODING from
    the MSB) followed by 4 don't-care bits sent as 0."""
    fields = [write, seq, 0, (add >> 2) & 1, (add >> 1) & 1, add & 1, (pm >> 1) & 1, pm & 1,
              shadow, 0, range_bit, coding, 0, 0, 0, 0]
    word = 0
    for b in fields:
        word = (word << 1) | b
    return word


def shadow_word(sequence_one: Sequence[int], sequence_two: Sequence[int] = ()) -> int:
    """The 16-bit shadow register word: VIN0..VIN7 of sequence one, then
    VIN0..VIN7 of sequence two, MSB first (Table 10)."""
    bits = [1 if c in set(sequence_one) else 0 for c in range(8)]
    bits += [1 if c in set(sequence_two) else 0 for c in range(8)]
    word = 0
    for b in bits:
        word = (word << 1) | b
    return word


class ReferenceDriver:
    """AD7927 driver in plain Python. Same calls as the C driver."""

    def __init__(self, bus: Any, *, frames: bool = False, range_double: bool = True,
                 twos_complement: bool = False, sample_after_fall: bool = False) -> None:
        self.bus = bus
        self.frames = frames
        self.range_bit = 0 if range_double else 1
        self.coding = 0 if twos_complement else 1
        self.sample_after_fall = sample_after_fall
        self.pending: int | None = None      # channel the next frame converts
        self.pending_coding = self.coding    # CODING in effect for that conversion
        self.sequence: list[int] = []        # running sequence, in conversion order
        self.position = 0                    # index of `pending` in it
        self.powered = False
        self.shut_down = False
        self.dirty = False                   # range/coding changed since the last write

    # -- frames ----------------------------------------------------------------
    def _pin_frames(self, words: Sequence[int], hold_ns: int) -> list[int]:
        p: Pins = self.bus
        out = []
        p.set_sclk(1)  # idle high
        for i, word in enumerate(words):
            p.set_cs(0)
            p.delay_ns(CS_TO_SCLK)
            got: list[int] = []
            for bit in [(word >> (15 - k)) & 1 for k in range(16)]:
                p.set_din(bit)
                p.delay_ns(DIN_SETUP)
                if not self.sample_after_fall:
                    got.append(p.get_dout())   # the bit on DOUT since the last falling edge
                p.set_sclk(0)                  # the part latches DIN, shifts DOUT
                if self.sample_after_fall:
                    got.append(p.get_dout())   # BROKEN: before the next bit is valid
                p.delay_ns(SCLK_LOW)
                p.set_sclk(1)
                p.delay_ns(SCLK_HIGH)
            p.set_cs(1)
            p.delay_ns(max(hold_ns, QUIET) if i == len(words) - 1 else QUIET)
            value = 0
            for b in got:
                value = (value << 1) | b
            out.append(value)
        return out

    def _transfer(self, words: Sequence[int], hold_ns: int = QUIET) -> list[int]:
        if self.frames:
            return [int(w) for w in self.bus.transfer(list(words), hold_ns)]
        return self._pin_frames(words, hold_ns)

    def _write(self, *, seq: int = 0, add: int = 0, shadow: int = 0, pm: int = NORMAL) -> int:
        return control_word(seq=seq, add=add, pm=pm, shadow=shadow, range_bit=self.range_bit,
                            coding=self.coding)

    def _check(self, word: int, channel: int | None, coding: int, lead_only: bool = False) -> int:
        """The code in ``word`` after checking it names ``channel`` (None: nothing to check)."""
        if channel is None:
            return 0
        if word >> 15:
            self._lost()
            raise FrameError(f"AD7927 output word 0x{word:04X} has a leading 1", word, channel)
        if not lead_only and (word >> 12) & 7 != channel:
            self._lost()
            raise AddressMismatch(f"AD7927 output word 0x{word:04X} names VIN{(word >> 12) & 7}, "
                                  f"expected VIN{channel}", word, channel)
        data = word & 0xFFF
        if coding:
            return data
        return data - 4096 if data & 0x800 else data

    def _lost(self) -> None:
        self.pending = None
        self.sequence = []

    def _wake(self, word: int) -> None:
        self._transfer([word], POWER_UP)       # invalid conversion: not checked
        self.shut_down = False
        self.dirty = False
        self.pending_coding = self.coding

    # -- API -------------------------------------------------------------------
    def configure(self, *, range_double: bool = True, twos_complement: bool = False) -> None:
        r, c = (0 if range_double else 1), (0 if twos_complement else 1)
        if (r, c) != (self.range_bit, self.coding):
            self.range_bit, self.coding, self.dirty = r, c, True

    def power_up(self) -> None:
        """Two frames with DIN high, each followed by t_POWER-UP (either may
        be the write that wakes a shut-down part), then the first write (VIN0
        next); the third frame converts VIN0 of the all-ones sequence."""
        self.powered = self.shut_down = self.dirty = False
        self._lost()
        self._transfer([0xFFFF], POWER_UP)
        self._transfer([0xFFFF], POWER_UP)
        (out,) = self._transfer([self._write(add=0)])
        self._check(out, 0, 1)
        self.powered = True
        self.pending, self.pending_coding = 0, self.coding

    def _need_power(self) -> None:
        if not self.powered:
            raise DeviceError("AD7927: power_up() first")

    def scan(self, channels: Sequence[int], next_channel: int | None = None) -> list[int]:
        chans = [int(c) for c in channels]
        if not 1 <= len(chans) <= 16 or any(not 0 <= c <= 7 for c in chans):
            raise InvalidArgument(f"channels must be 1..16 channels 0..7, got {chans}")
        nxt = chans[0] if next_channel is None else int(next_channel)
        if not 0 <= nxt <= 7:
            raise InvalidArgument(f"next_channel must be 0..7, got {next_channel!r}")
        self._need_power()
        if self.shut_down:
            self._wake(self._write(add=chans[0]))
            self.sequence, self.pending = [], chans[0]
        words, expect = [], []
        if self.pending != chans[0] or self.sequence or self.dirty:
            words.append(self._write(add=chans[0]))
            expect.append((self.pending, self.pending_coding))
        for i, c in enumerate(chans):
            words.append(self._write(add=chans[i + 1] if i + 1 < len(chans) else nxt))
            expect.append((c, self.pending_coding if not expect else self.coding))
        out = self._transfer(words)
        self.dirty = False
        codes = [self._check(w, ch, cod) for w, (ch, cod) in zip(out, expect)]
        self.pending, self.pending_coding, self.sequence = nxt, self.coding, []
        return codes[len(codes) - len(chans):]

    def _sequence_write(self, word: int) -> None:
        if self.shut_down:
            self._wake(word)
            return
        (out,) = self._transfer([word])
        self.dirty = False
        self._check(out, self.pending, self.pending_coding)
        self.pending_coding = self.coding

    def seq_start(self, last: int) -> None:
        """Consecutive sequence VIN0..VIN`last` (SEQ = 1, SHADOW = 1)."""
        if not 0 <= int(last) <= 7:
            raise InvalidArgument(f"last must be 0..7, got {last!r}")
        self._need_power()
        self._sequence_write(self._write(seq=1, shadow=1, add=int(last)))
        self.sequence, self.position, self.pending = list(range(int(last) + 1)), 0, 0

    def shadow_start(self, sequence_one: Sequence[int], sequence_two: Sequence[int] = ()) -> None:
        """Shadow-register sequences (SEQ = 0, SHADOW = 1, then the shadow word)."""
        one = sorted({int(c) for c in sequence_one})
        two = sorted({int(c) for c in sequence_two})
        if not one or any(not 0 <= c <= 7 for c in one + two):
            raise InvalidArgument(f"sequence_one must name 1+ channels 0..7 (and sequence_two "
                                  f"0..7), got {list(sequence_one)} / {list(sequence_two)}")
        self._need_power()
        self._sequence_write(self._write(shadow=1, add=0))
        (out,) = self._transfer([shadow_word(one, two)])
        self._check(out, 0, 1, lead_only=True)  # the load frame's channel is not documented
        self.sequence, self.position, self.pending = one + two, 0, one[0]

    def seq_read(self, n: int) -> tuple[list[int], list[int]]:
        """n conversions of the running sequence: (codes, channels)."""
        if not 1 <= int(n) <= 16:
            raise InvalidArgument(f"n must be 1..16, got {n!r}")
        if not self.sequence or self.shut_down:
            raise DeviceError("AD7927: no sequence is running")
        words = [0] * int(n)                      # WRITE = 0: the sequence runs on
        if self.dirty:
            words[0] = self._write(seq=1)         # SEQ = 1, SHADOW = 0: new mode, same sequence
        out = self._transfer(words)
        self.dirty = False
        codes, chans = [], []
        for i, w in enumerate(out):
            ch = self.sequence[self.position]
            codes.append(self._check(w, ch, self.pending_coding if i == 0 else self.coding))
            chans.append(ch)
            self.position = (self.position + 1) % len(self.sequence)
        self.pending, self.pending_coding = self.sequence[self.position], self.coding
        return codes, chans

    def power_down(self) -> None:
        """Full shutdown (PM = 10)."""
        self._need_power()
        if self.shut_down:
            return
        (out,) = self._transfer([self._write(pm=FULL_SHUTDOWN)])
        self.dirty, self.shut_down = False, True
        try:
            self._check(out, self.pending, self.pending_coding)
        finally:
            self._lost()
