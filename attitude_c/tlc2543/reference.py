"""Pure-Python reference driver for the TLC2543, written from the datasheet.

The second opinion on the C driver: it implements the same I/O cycle from
the TLC2543 timing diagram (docs/tlc2543.md, "The I/O cycle") on any object
with the pin operations of the device model (``set_cs``, ``set_clock``,
``set_din``, ``get_dout``, ``get_eoc``, ``delay_ns``), with its own copy of
the datasheet limits. It is deliberately simple (lists of bits, no shift
register tricks) and shares no code with csrc/src/tlc2543.c.

``sample_after_fall=True`` is a deliberately broken variant: it samples
DATA OUT right after the falling edge (on the wrong edge, before the next
bit is valid) — the model must catch it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

from ..errors import DeviceError, DeviceTimeout, InvalidArgument

# Datasheet limits the reference driver waits for (ns).
CS_SETUP = 1425        # CS low -> first clock; DATA OUT valid after CS low
DIN_SETUP = 100        # DATA INPUT setup before the rising edge
CLOCK_HIGH = 122       # 4.1 MHz max I/O clock: >= 122 ns high ...
DOUT_VALID = 240       # ... and the next DATA OUT bit is valid 240 ns after the fall
EOC_DELAY = 2200       # EOC falls up to 2.2 us after the last clock
EOC_POLL = 1000        # spacing of EOC samples
CS_REASSERT = 5000     # CS must stay high 5 us after the last clock

LENGTH_BITS = {8: 0b01, 12: 0b00, 16: 0b11}
SELFTEST = ((11, 0x800), (12, 0x000), (13, 0xFFF))
SELFTEST_TOL = 2  # LSB: datasheet total unadjusted error (+-1) + 1 LSB reference noise


class Pins(Protocol):
    def set_cs(self, level: int) -> None: ...
    def set_clock(self, level: int) -> None: ...
    def set_din(self, level: int) -> None: ...
    def get_dout(self) -> int: ...
    def get_eoc(self) -> int: ...
    def delay_ns(self, ns: int) -> None: ...


class ReferenceDriver:
    """TLC2543 driver in plain Python (reads through a pin object)."""

    def __init__(self, pins: Pins, *, length: int = 12, lsb_first: bool = False,
                 bipolar: bool = False, eoc_polls: int = 40, sample_after_fall: bool = False) -> None:
        if length not in LENGTH_BITS:
            raise InvalidArgument(f"length must be 8, 12 or 16, got {length!r}")
        self.pins = pins
        self.length = length
        self.lsb_first = bool(lsb_first)
        self.bipolar = bool(bipolar)
        self.eoc_polls = eoc_polls
        self.sample_after_fall = sample_after_fall
        self.pending: int | None = None  # address whose result the output register holds

    def _control_bits(self, address: int) -> list[int]:
        byte = (address << 4) | (LENGTH_BITS[self.length] << 2) | (int(self.lsb_first) << 1) | int(self.bipolar)
        return [(byte >> (7 - i)) & 1 for i in range(8)]

    def _word(self, bits: list[int]) -> int:
        if self.lsb_first:
            bits = bits[::-1]
        word = 0
        for b in bits:
            word = (word << 1) | b
        if self.bipolar and bits[0]:
            word -= 1 << self.length
        return word

    def io_cycle(self, address: int) -> int:
        """One I/O cycle sending ``address``; returns the word clocked out
        (the conversion requested by the previous cycle)."""
        if not 0 <= address <= 14:
            raise InvalidArgument(f"address must be 0..14, got {address}")
        p = self.pins
        din = self._control_bits(address)
        got: list[int] = []
        p.set_cs(0)
        p.delay_ns(CS_SETUP)
        for i in range(self.length):
            if i < 8:
                p.set_din(din[i])          # DATA INPUT only matters on clocks 1..8
            p.delay_ns(DIN_SETUP)
            if not self.sample_after_fall:
                got.append(p.get_dout())   # bit i, valid since CS fell / the last fall
            p.set_clock(1)                 # the chip samples DATA INPUT here
            p.delay_ns(CLOCK_HIGH)
            p.set_clock(0)                 # ... and shifts DATA OUT here
            if self.sample_after_fall:
                got.append(p.get_dout())   # BROKEN: too early, and one bit late
            p.delay_ns(DOUT_VALID)
        p.set_cs(1)
        word = self._word(got)
        # EOC is undefined for 2.2 us after the last clock, then low until the
        # conversion ends. Power-down converts nothing (EOC stays high), but CS
        # must still stay high 5 us: wait that long, then check EOC all the same.
        p.delay_ns(CS_REASSERT if address == 14 else EOC_DELAY)
        for _ in range(self.eoc_polls):
            if p.get_eoc():
                self.pending = None if address == 14 else address
                return word
            if _ + 1 < self.eoc_polls:
                p.delay_ns(EOC_POLL)
        self.pending = None
        raise DeviceTimeout(f"TLC2543 EOC did not rise within {self.eoc_polls} samples")

    def scan(self, channels: Sequence[int], next_address: int | None = None) -> list[int]:
        """Read ``channels`` (addresses 0..13) in the fewest cycles; the last
        cycle requests ``next_address`` (default: channels[0], so that the
        next scan of the same list needs one cycle less)."""
        chans = [int(c) for c in channels]
        if not chans or any(not 0 <= c <= 13 for c in chans):
            raise InvalidArgument(f"channels must be 1+ addresses in 0..13, got {chans}")
        nxt = chans[0] if next_address is None else int(next_address)
        if self.pending != chans[0]:
            self.io_cycle(chans[0])        # the stale word is discarded
        out = []
        for c in chans[1:] + [nxt]:
            out.append(self.io_cycle(c))
        return out

    def self_test(self) -> list[int]:
        """Convert the three test voltages (12-bit, MSB first, unipolar) and
        check them; raises DeviceError naming the bad one."""
        saved = (self.length, self.lsb_first, self.bipolar)
        self.length, self.lsb_first, self.bipolar = 12, False, False
        self.pending = None
        try:
            codes = self.scan([a for a, _ in SELFTEST], next_address=11)
        finally:
            self.length, self.lsb_first, self.bipolar = saved
            self.pending = None
        for (address, want), got in zip(SELFTEST, codes):
            if abs(got - want) > SELFTEST_TOL:
                raise DeviceError(f"TLC2543 self-test: address {address} gave 0x{got:03X}, "
                                  f"expected 0x{want:03X} +- {SELFTEST_TOL}")
        return codes
