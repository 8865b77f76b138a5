"""Pin-level behavioural model of the TI TLC2543 12-bit serial ADC.

The model is driven through the same seven pin operations as the C driver's
HAL (``set_cs``, ``set_clock``, ``set_din``, ``get_dout``, ``get_eoc``,
``delay_ns``). Time only advances in :meth:`Tlc2543Model.delay_ns`; pin
operations take no time. Every protocol or timing violation raises
:class:`ProtocolViolation` (``rule`` names the broken rule), and every pin
change and pin read is recorded in :attr:`Tlc2543Model.trace`.

Behaviour (docs/tlc2543.md has the full I/O-cycle description):

* CS falling starts an I/O cycle; DATA OUT leaves high impedance and shows
  the first bit of the output register. DATA INPUT is sampled on the rising
  edges 1..8 (input byte MSB first: address D7-D4, length D3-D2, LSB-first
  D1, bipolar D0). DATA OUT shifts to the next bit on every falling edge.
* The cycle has 8, 12 or 16 clocks, chosen by D3-D2 of the byte clocked in
  during that same cycle. On the last falling edge the analog input of the
  addressed channel is sampled and converted: EOC falls ``t_eoc_fall_ns``
  later and rises ``t_conv_ns`` after that edge, when the output register
  receives the result formatted with that request's length/LSBF/BIP.
* The 12-bit code is ``clip(floor((v - vref_minus) / (vref_plus -
  vref_minus) * 4096 + 0.5), 0, 4095)`` (inputs beyond the rails clip);
  bipolar codes are that XOR 0x800 (two's complement about mid-scale).
  8-bit words are the 8 MSBs, 16-bit words are the code followed by four 0s.
* Address 11/12/13 converts (Vref+ + Vref-)/2, Vref-, Vref+; address 14 is
  software power-down (no conversion, EOC stays high, output register
  undefined); address 15 is reserved (a violation).

Trace entries are ``(t_ns, signal, value)`` with ``signal`` in
:data:`SIGNALS`: driven pins ``CS``/``CLOCK``/``DIN`` (recorded when their
level changes), device outputs ``DOUT``/``EOC`` (when they change; DOUT
value 2 = high impedance) and reads ``DOUT?``/``EOC?`` (value read).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .._devmodel import PinModel, ProtocolViolationBase, check_inputs, check_level
from ..errors import InvalidArgument, NonFiniteError

#: Trace signal names, in the order of the C twin's codes.
SIGNALS = ("CS", "CLOCK", "DIN", "DOUT", "EOC", "DOUT?", "EOC?")
#: DATA OUT value in the trace while CS is high (high impedance).
HIGH_Z = PinModel.HIGH_Z

#: Rules checked by the model (ProtocolViolation.rule), in the order of the
#: C twin's violation codes (1-based there; 0 = none).
RULES = (
    "clock-count",          # more clocks than the programmed length
    "cs-mid-cycle",         # CS raised before the programmed number of clocks
    "dout-early",           # DATA OUT read before it is valid
    "dout-cs-high",         # DATA OUT read while CS is high (high impedance)
    "clock-too-fast",       # I/O CLOCK high or low shorter than allowed
    "cs-setup",             # first clock too soon after CS fell
    "cs-too-early",         # CS fell again within t_cs_reassert of the last clock
    "cs-during-conversion", # CS fell before the conversion ended (aborts it)
    "eoc-early",            # EOC sampled before it is meaningful
    "din-setup",            # DATA INPUT changed too close before a rising edge
    "din-hold",             # DATA INPUT changed too soon after a rising edge
    "clock-cs-high",        # I/O CLOCK toggled while CS is high
    "clock-high-at-cs",     # CS changed while I/O CLOCK is high
    "reserved-address",     # address 15
)


class ProtocolViolation(ProtocolViolationBase):
    """The driver broke a TLC2543 protocol or timing rule.

    ``rule`` is one of :data:`RULES`; ``time_ns`` is the model time.
    """

    device = "TLC2543"


@dataclass(frozen=True)
class Timing:
    """Datasheet timing limits (ns) enforced by the model, and its behaviour.

    The limit values are those the driver is written against
    (csrc/src/tlc2543.c); see docs/tlc2543.md for their sources.
    """

    t_cs_setup: int = 1425     #: CS low -> first I/O CLOCK rise (min)
    t_dout_enable: int = 1425  #: CS low -> first DATA OUT bit valid (max)
    t_din_setup: int = 100     #: DATA INPUT stable before a rise (min)
    t_din_hold: int = 5        #: DATA INPUT stable after a rise (min)
    t_clk_high: int = 122      #: I/O CLOCK high (min): 4.1 MHz max
    t_clk_low: int = 122       #: I/O CLOCK low (min)
    t_dout_valid: int = 240    #: I/O CLOCK fall -> next DATA OUT bit valid (max)
    t_eoc_fall: int = 2200     #: last clock fall -> EOC low (max; EOC undefined before)
    t_conv: int = 10000        #: last clock fall -> EOC high, result ready (max)
    t_cs_reassert: int = 5000  #: last clock fall -> CS may fall again (min)


def quantize(v: float, vref_plus: float, vref_minus: float = 0.0) -> int:
    """The 12-bit unipolar code of ``v`` (clipped at the rails)."""
    x = (v - vref_minus) / (vref_plus - vref_minus)
    c = math.floor(x * 4096.0 + 0.5)
    return 0 if c < 0 else 4095 if c > 4095 else int(c)


def format_bits(code12: int, mode: int) -> list[int]:
    """Bits of the output register for a 12-bit unipolar ``code12`` formatted
    with the request's mode nibble (D3-D2 length, D1 LSB first, D0 bipolar),
    in shifting order."""
    code = code12 ^ 0x800 if mode & 1 else code12
    length = (mode >> 2) & 3
    if length == 1:
        nbits, word = 8, code >> 4
    elif length == 3:
        nbits, word = 16, code << 4
    else:
        nbits, word = 12, code
    bits = [(word >> (nbits - 1 - i)) & 1 for i in range(nbits)]
    return bits[::-1] if mode & 2 else bits


def clocks_of(in_byte: int) -> int:
    length = (in_byte >> 2) & 3
    return 8 if length == 1 else 16 if length == 3 else 12


class Tlc2543Model(PinModel):
    """Pin-level TLC2543 with simulated time (ns). See the module docstring.

    ``inputs``: voltages of AIN0..AIN10 (V). ``stuck_eoc`` / ``stuck_dout``:
    None, 0 or 1 — a pin stuck at that level (fault injection). The output
    register holds ``powerup_word`` (12-bit, MSB first) until the first
    conversion ends.
    """

    violation = ProtocolViolation

    def __init__(self, inputs: Sequence[float] | np.ndarray = (), *, vref_plus: float = 5.0,
                 vref_minus: float = 0.0, timing: Timing | None = None,
                 stuck_eoc: int | None = None, stuck_dout: int | None = None,
                 powerup_word: int = 0xA5A, record: bool = True) -> None:
        if not (math.isfinite(vref_plus) and math.isfinite(vref_minus)):
            raise NonFiniteError("vref_plus/vref_minus must be finite")
        if not vref_plus > vref_minus:
            raise InvalidArgument(f"vref_plus ({vref_plus}) must be above vref_minus ({vref_minus})")
        check_level("stuck_eoc", stuck_eoc)
        check_level("stuck_dout", stuck_dout)
        self.vref_plus = float(vref_plus)
        self.vref_minus = float(vref_minus)
        self.timing = timing or Timing()
        self.stuck_eoc = stuck_eoc
        self.stuck_dout = stuck_dout
        self.record = record
        self.inputs = np.zeros(11)
        self.set_inputs(inputs)
        self.trace: list[tuple[int, str, int]] = []
        self.t = 0
        # pins driven by the MCU
        self.cs, self.clock, self.din = 1, 0, 0
        self.t_din = -(10 ** 9)  # last DATA INPUT change
        # device state
        self.out_bits = format_bits(powerup_word & 0xFFF, 0)
        self.dout_level = HIGH_Z
        self.eoc_level = 1 if stuck_eoc is None else stuck_eoc
        self.conversions = 0  # conversions completed (for tests)
        self._reset_cycle()
        self.t_last_clock: int | None = None  # last falling edge of the last cycle
        self.conv_end: int | None = None      # end of the running conversion
        self.pending: tuple[int, int] | None = None  # (address, mode) being converted
        self.eoc_fall_at: int | None = None

    # -- configuration ------------------------------------------------------
    def set_inputs(self, inputs: Sequence[float] | np.ndarray) -> None:
        """Set AIN0.. (up to 11 voltages, V); missing ones keep their value."""
        v = check_inputs(inputs, 11, "AIN")
        self.inputs[: v.size] = v

    # -- internals -----------------------------------------------------------
    def _reset_cycle(self) -> None:
        self.n_rise = 0
        self.n_fall = 0
        self.in_byte = 0
        self.nclk: int | None = None
        self.t_cs_fall = 0
        self.t_rise = -(10 ** 9)
        self.t_fall = -(10 ** 9)

    def _set_eoc(self, level: int) -> None:
        if self.stuck_eoc is not None:
            level = self.stuck_eoc
        if level != self.eoc_level:
            self.eoc_level = level
            self._log("EOC", level)

    def _bit(self, index: int) -> int:
        return self.out_bits[index] if index < len(self.out_bits) else 0

    def _advance_to(self, t_new: int) -> None:
        """Apply device events scheduled up to t_new, in time order."""
        while True:
            events = []
            if self.eoc_fall_at is not None and self.eoc_fall_at <= t_new:
                events.append((self.eoc_fall_at, 0))
            if self.conv_end is not None and self.conv_end <= t_new and self.pending is not None:
                events.append((self.conv_end, 1))
            if not events:
                break
            t_ev, kind = min(events)
            self.t = t_ev
            if kind == 0:
                self.eoc_fall_at = None
                self._set_eoc(0)
            else:
                self._finish_conversion()
        self.t = t_new

    def _finish_conversion(self) -> None:
        assert self.pending is not None
        address, mode = self.pending
        self.pending = None
        if address <= 10:
            v = float(self.inputs[address])
        elif address == 11:
            v = (self.vref_plus + self.vref_minus) / 2.0
        elif address == 12:
            v = self.vref_minus
        else:
            v = self.vref_plus
        self.out_bits = format_bits(quantize(v, self.vref_plus, self.vref_minus), mode)
        self.conversions += 1
        self._set_eoc(1)

    def _end_of_cycle(self) -> None:
        """Last falling edge: start the conversion requested by this cycle."""
        address = self.in_byte >> 4
        self.t_last_clock = self.t
        if address == 15:
            self._fail("reserved-address", "address 15 is reserved (factory test)")
        if address == 14:  # power-down: no conversion, output undefined
            self.out_bits = format_bits(0xA5A, 0)
            self.conv_end = None
            self.pending = None
            return
        self.pending = (address, self.in_byte & 0x0F)
        self.conv_end = self.t + self.timing.t_conv
        self.eoc_fall_at = self.t + self.timing.t_eoc_fall

    # -- HAL operations --------------------------------------------------------
    def delay_ns(self, ns: int) -> None:
        if ns < 0:
            raise InvalidArgument(f"delay_ns: negative delay {ns}")
        self._advance_to(self.t + int(ns))

    def set_cs(self, level: int) -> None:
        level = 1 if level else 0
        if level == self.cs:
            return
        tm = self.timing
        if self.clock:
            self._fail("clock-high-at-cs", "CS changed while I/O CLOCK is high")
        if level == 0:
            if self.t_last_clock is not None and self.t - self.t_last_clock < tm.t_cs_reassert:
                self._fail("cs-too-early",
                           f"CS fell {self.t - self.t_last_clock} ns after the last I/O clock "
                           f"(min {tm.t_cs_reassert} ns): the conversion would abort")
            if self.pending is not None:
                self._fail("cs-during-conversion",
                           f"CS fell {self.conv_end - self.t} ns before the conversion ends "  # type: ignore[operator]
                           "(it would abort)")
            self.cs = 0
            self._log("CS", 0)
            self._reset_cycle()
            self.t_cs_fall = self.t
            self._set_dout(self._bit(0))
        else:
            if self.nclk is None or self.n_fall < self.nclk:
                need = self.nclk if self.nclk is not None else "8/12/16"
                self._fail("cs-mid-cycle",
                           f"CS raised after {self.n_fall} I/O clocks of {need}")
            self.cs = 1
            self._log("CS", 1)
            self._set_dout(HIGH_Z)

    def set_clock(self, level: int) -> None:
        level = 1 if level else 0
        if level == self.clock:
            return
        tm = self.timing
        if self.cs:
            self._fail("clock-cs-high", "I/O CLOCK toggled while CS is high")
        if level == 1:
            if self.n_rise == 0:
                if self.t - self.t_cs_fall < tm.t_cs_setup:
                    self._fail("cs-setup", f"first I/O clock {self.t - self.t_cs_fall} ns after CS fell "
                               f"(min {tm.t_cs_setup} ns)")
            elif self.t - self.t_fall < tm.t_clk_low:
                self._fail("clock-too-fast", f"I/O CLOCK low for {self.t - self.t_fall} ns "
                           f"(min {tm.t_clk_low} ns: 4.1 MHz)")
            if self.nclk is not None and self.n_rise >= self.nclk:
                self._fail("clock-count", f"I/O clock {self.n_rise + 1} in a {self.nclk}-clock cycle")
            if self.n_rise < 8:
                if self.t - self.t_din < tm.t_din_setup:
                    self._fail("din-setup", f"DATA INPUT changed {self.t - self.t_din} ns before "
                               f"the rising edge (min {tm.t_din_setup} ns)")
                self.in_byte = (self.in_byte << 1) | self.din
            self.n_rise += 1
            if self.n_rise == 8:
                self.nclk = clocks_of(self.in_byte)
            self.clock = 1
            self.t_rise = self.t
            self._log("CLOCK", 1)
        else:
            if self.t - self.t_rise < tm.t_clk_high:
                self._fail("clock-too-fast", f"I/O CLOCK high for {self.t - self.t_rise} ns "
                           f"(min {tm.t_clk_high} ns: 4.1 MHz)")
            self.clock = 0
            self.n_fall += 1
            self.t_fall = self.t
            self._log("CLOCK", 0)
            if self.nclk is not None and self.n_fall == self.nclk:
                self._end_of_cycle()
            else:
                self._set_dout(self._bit(self.n_fall))

    def set_din(self, level: int) -> None:
        level = 1 if level else 0
        if level == self.din:
            return
        if self.clock and self.t - self.t_rise < self.timing.t_din_hold:
            self._fail("din-hold", f"DATA INPUT changed {self.t - self.t_rise} ns after the rising "
                       f"edge (min {self.timing.t_din_hold} ns)")
        self.din = level
        self.t_din = self.t
        self._log("DIN", level)

    def get_dout(self) -> int:
        tm = self.timing
        if self.cs:
            self._fail("dout-cs-high", "DATA OUT read while CS is high (high impedance)")
        if self.n_fall == 0:
            if self.t - self.t_cs_fall < tm.t_dout_enable:
                self._fail("dout-early", f"DATA OUT read {self.t - self.t_cs_fall} ns after CS fell "
                           f"(valid after {tm.t_dout_enable} ns)")
        elif self.t - self.t_fall < tm.t_dout_valid:
            self._fail("dout-early", f"DATA OUT read {self.t - self.t_fall} ns after I/O CLOCK fell "
                       f"(next bit valid after {tm.t_dout_valid} ns)")
        if self.nclk is not None and self.n_fall >= self.nclk:
            self._fail("dout-early", "DATA OUT read after the last bit of the cycle")
        v = self.dout_level
        self._log("DOUT?", v)
        return v

    def get_eoc(self) -> int:
        if self.t_last_clock is not None and self.t - self.t_last_clock < self.timing.t_eoc_fall \
                and self.pending is not None:
            self._fail("eoc-early", f"EOC sampled {self.t - self.t_last_clock} ns after the last "
                       f"I/O clock (undefined until {self.timing.t_eoc_fall} ns)")
        v = self.eoc_level
        self._log("EOC?", v)
        return v

    # -- helpers for tests -----------------------------------------------------
    def code_of(self, address: int) -> int:
        """The 12-bit unipolar code the model would produce for ``address`` now."""
        if address <= 10:
            v = float(self.inputs[address])
        elif address == 11:
            v = (self.vref_plus + self.vref_minus) / 2.0
        elif address == 12:
            v = self.vref_minus
        elif address == 13:
            v = self.vref_plus
        else:
            raise InvalidArgument(f"address {address} has no conversion")
        return quantize(v, self.vref_plus, self.vref_minus)
