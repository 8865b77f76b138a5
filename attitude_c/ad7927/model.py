"""Behavioural model of the Analog Devices AD7927 (8 channels, 12 bits, SPI).

Two ways in, one device behind them:

* **pins** — the five operations of the bit-banged HAL (``set_cs``,
  ``set_sclk``, ``set_din``, ``get_dout``, ``delay_ns``), checked against
  the datasheet's serial-interface timing;
* **frames** — :meth:`Ad7927Model.transfer`, what a hardware SPI controller
  does (n 16-bit frames, CS high between them), checked at frame level
  (quiet time, power-up time).

Time is simulated (ns) and only advances in ``delay_ns`` (and, at frame
level, by 16 SCLK periods per frame). Every protocol or timing violation
raises :class:`ProtocolViolation` (``rule`` names the broken rule). Pin
changes and DOUT reads are recorded in :attr:`Ad7927Model.trace`, every
completed frame in :attr:`Ad7927Model.frames`.

Behaviour (datasheet Rev. D; docs/ad7927.md says where it was interpreted):

* CS falling: the input of the channel selected by the previous frame is
  sampled and converted during this frame; DOUT leaves three-state with the
  leading zero. DIN is latched and DOUT shifted on SCLK falling edges: after
  falling edge k DOUT shows bit 15 - k of the output word (leading 0,
  ADD2..ADD0 of the converted channel, 12 data bits MSB first); on the 16th
  falling edge DOUT returns to three-state.
* CS rising after 16 falling edges: the DIN word takes effect — a shadow
  register load if the previous write asked for one (SEQ = 0, SHADOW = 1),
  else a control write if its MSB (WRITE) is 1, else nothing (WRITE = 0:
  a running sequence advances, otherwise the same channel again). CS rising
  earlier aborts the conversion and changes nothing.
* Control writes (bits 15..4 of the DIN word): SEQ/SHADOW 00 selects ADD for
  the next conversion, 01 as 00 plus a shadow load in the next frame, 11
  starts the consecutive sequence VIN0..VIN(ADD), 10 keeps a running
  sequence going (or acts as 00 without one). A shadow load starts the
  sequence: its sequence-one channels ascending, then its sequence-two
  channels, around again.
* Codes: ``floor(v / span * 4096)`` clipped to 0..4095, span = REFIN
  (RANGE = 1) or 2 REFIN (RANGE = 0); two's complement (CODING = 0) is that
  code XOR 0x800 in the 12 data bits.
* Power: PM = 11 normal; 10 full shutdown from that CS rising edge; 01 auto
  shutdown after each valid conversion, woken by the next CS falling edge
  (that frame's conversion is invalid). A conversion is invalid while the
  part is shut down (the word is ``garbage`` with the leading zero);
  leaving full shutdown (a PM = 11 write) needs ``t_power_up`` from that CS
  rising edge, waking from auto shutdown ``t_power_up`` from the waking CS
  falling edge, before the next conversion (rule ``power-up-time``).
* Power-on: the part may wake in any mode; ``powerup_control`` (control
  register) and ``powerup_shadow`` (the next frame loads the shadow
  register) choose it. The default is the worst case: full shutdown and a
  pending shadow load.

Trace entries are ``(t_ns, signal, value)`` with ``signal`` in
:data:`SIGNALS`: driven pins ``CS``/``SCLK``/``DIN`` (when their level
changes), ``DOUT`` (when the part changes it; 2 = three-state) and reads
``DOUT?`` (the value read).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .._devmodel import PinModel, ProtocolViolationBase, check_inputs, check_level
from ..errors import InvalidArgument

#: Trace signal names, in the order of the C twin's codes.
SIGNALS = ("CS", "SCLK", "DIN", "DOUT", "DOUT?")
#: DOUT value in the trace while it is three-state.
HIGH_Z = PinModel.HIGH_Z

#: Rules checked by the model (ProtocolViolation.rule), in the order of the
#: C twin's violation codes (1-based there; 0 = none).
RULES = (
    "clock-count",         # a 17th SCLK falling edge while CS is low
    "cs-early",            # CS raised before the 16th falling edge (conversion aborted)
    "cs-hold",             # CS raised < t_cs_hold after the 16th falling edge
    "cs-setup",            # first SCLK falling edge < t_cs_sclk after CS fell
    "quiet-time",          # CS fell < t_quiet after it rose
    "clock-too-fast",      # SCLK period < t_sclk_period, or a phase < 0.4 period
    "clock-too-slow",      # SCLK period > t_sclk_period_max (f_SCLK < 10 kHz)
    "din-setup",           # DIN changed < t_din_setup before a falling edge
    "din-hold",            # DIN changed < t_din_hold after a falling edge
    "dout-early",          # DOUT read before the bit is valid
    "dout-three-state",    # DOUT read while CS is high or after the 16th falling edge
    "power-up-time",       # conversion started < t_power_up after the part began powering up
    "invalid-power-mode",  # a control write with PM1 PM0 = 00
)

PM_NORMAL, PM_FULL, PM_AUTO = 3, 2, 1
#: Default power-on state: full shutdown (PM = 10), shadow load pending.
POWERUP_CONTROL = PM_FULL << 4
#: DOUT word of an invalid conversion (leading zero kept).
GARBAGE = 0x5A5A


class ProtocolViolation(ProtocolViolationBase):
    """The driver broke an AD7927 protocol or timing rule.

    ``rule`` is one of :data:`RULES`; ``time_ns`` is the model time.
    """

    device = "AD7927"


@dataclass(frozen=True)
class Timing:
    """Datasheet timing (ns) enforced by the model (AD7908/AD7918/AD7928 and
    AD7927 serial-interface specifications; 3 V column where they differ)."""

    t_cs_sclk: int = 10           #: t2: CS low -> first SCLK falling edge (min)
    t_dout_enable: int = 35       #: t3: CS low -> leading zero valid on DOUT (max)
    t_dout_access: int = 40       #: t4: SCLK falling edge -> next DOUT bit valid (max)
    t_sclk_period: int = 50       #: 1 / f_SCLK max (20 MHz); each phase >= 0.4 period (t5, t6)
    t_sclk_period_max: int = 100_000  #: 1 / f_SCLK min (10 kHz)
    t_din_setup: int = 10         #: t9: DIN stable before a falling edge (min)
    t_din_hold: int = 5           #: t10: DIN stable after a falling edge (min)
    t_cs_hold: int = 20           #: t11: 16th falling edge -> CS high (min)
    t_quiet: int = 50             #: t_QUIET: CS high between frames (min)
    t_power_up: int = 1000        #: t12: power-up from full/auto shutdown (max)


@dataclass(frozen=True)
class Frame:
    """One completed frame: CS falling time, DIN word latched, DOUT word
    driven, the channel converted and whether that conversion was valid."""

    t: int
    din: int
    dout: int
    channel: int
    valid: bool


def quantize(v: float, refin: float, range_double: bool = True) -> int:
    """The straight-binary 12-bit code of ``v`` (clipped at the range ends)."""
    span = 2.0 * refin if range_double else refin
    c = math.floor(v / span * 4096.0)
    return 0 if c < 0 else 4095 if c > 4095 else int(c)


def shadow_channels(shadow: int) -> list[int]:
    """The channel order a shadow word programs: sequence one (bits 15..8 =
    VIN0..VIN7) ascending, then sequence two (bits 7..0 = VIN0..VIN7)."""
    one = [c for c in range(8) if (shadow >> (15 - c)) & 1]
    two = [c for c in range(8) if (shadow >> (7 - c)) & 1]
    return one + two


class Ad7927Model(PinModel):
    """AD7927 with simulated time (ns). See the module docstring.

    ``inputs``: VIN0..VIN7 in volts; ``refin``: REFIN (V). Faults:
    ``stuck_dout`` / ``stuck_din`` (None, 0 or 1: the pin as the part drives
    or sees it), ``address_xor`` (0..7, XORed into the channel address of
    every output word). ``sclk_period_ns``: SCLK period of frame-level
    transfers (default 108 ns = 9.26 MHz, the thesis's SPI0).
    """

    violation = ProtocolViolation

    def __init__(self, inputs: Sequence[float] | np.ndarray = (), *, refin: float = 2.5,
                 timing: Timing | None = None, powerup_control: int = POWERUP_CONTROL,
                 powerup_shadow: bool = True, stuck_dout: int | None = None,
                 stuck_din: int | None = None, address_xor: int = 0, garbage: int = GARBAGE,
                 sclk_period_ns: int = 108, record: bool = True) -> None:
        if not (isinstance(refin, (int, float)) and math.isfinite(refin) and refin > 0):
            raise InvalidArgument(f"refin must be a positive finite voltage, got {refin!r}")
        check_level("stuck_dout", stuck_dout)
        check_level("stuck_din", stuck_din)
        if not 0 <= int(address_xor) <= 7:
            raise InvalidArgument(f"address_xor must be 0..7, got {address_xor!r}")
        if not 0 <= int(powerup_control) <= 0xFFF or (powerup_control >> 4) & 3 == 0:
            raise InvalidArgument(f"powerup_control must be a 12-bit control word with PM != 00, "
                                  f"got {powerup_control!r}")
        if int(sclk_period_ns) < 1:
            raise InvalidArgument(f"sclk_period_ns must be positive, got {sclk_period_ns!r}")
        self.inputs = np.zeros(8)
        self.set_inputs(inputs)
        self.refin = float(refin)
        self.timing = timing or Timing()
        self.stuck_dout = stuck_dout
        self.stuck_din = stuck_din
        self.address_xor = int(address_xor)
        self.garbage = int(garbage) & 0x7FFF
        self.sclk_period_ns = int(sclk_period_ns)
        self.record = record
        self.trace: list[tuple[int, str, int]] = []
        self.frames: list[Frame] = []
        self.conversions = 0
        self.t = 0
        # pins
        self.cs, self.sclk, self.din = 1, 0, 0
        self.dout_level = HIGH_Z
        self.t_din = -10**9
        self.t_cs_rise: int | None = None
        self.t_cs_fall = 0
        self.t_fall: int | None = None
        self.t_rise: int | None = None
        self.n_fall = 0
        self.din_word = 0
        self.out_word = 0
        # the device
        cw = int(powerup_control)
        self.add = (cw >> 6) & 7
        self.range_bit = (cw >> 1) & 1
        self.coding = cw & 1
        self.pm = (cw >> 4) & 3
        self.powered = self.pm == PM_NORMAL
        self.ready_at: int | None = None
        self.shadow_pending = bool(powerup_shadow)
        self.seq: list[int] | None = None
        self.seq_pos = 0
        if (cw >> 10) & 1 and (cw >> 3) & 1:
            self.seq = list(range(self.add + 1))
        self.next_ch = self.seq[0] if self.seq else self.add
        self.converting = 0
        self.valid = False

    # -- configuration -----------------------------------------------------
    def set_inputs(self, inputs: Sequence[float] | np.ndarray) -> None:
        v = check_inputs(inputs, 8, "VIN")
        self.inputs[: v.size] = v

    # -- helpers -----------------------------------------------------------
    def code_of(self, channel: int) -> int:
        """The straight-binary code a valid conversion of ``channel`` gives now."""
        return quantize(float(self.inputs[channel]), self.refin, self.range_bit == 0)

    # -- the device: frame start and end -------------------------------------
    def _begin(self) -> None:
        """CS falling edge: sample and start converting; set out_word."""
        tm = self.timing
        if self.t_cs_rise is not None and self.t - self.t_cs_rise < tm.t_quiet:
            self._fail("quiet-time", f"CS fell {self.t - self.t_cs_rise} ns after it rose "
                       f"(min {tm.t_quiet} ns)")
        if not self.powered:
            self.valid = False
            if self.pm == PM_AUTO:  # this edge wakes the part; the conversion is a dummy
                self.powered = True
                self.ready_at = self.t + tm.t_power_up
        else:
            if self.ready_at is not None and self.t < self.ready_at:
                self._fail("power-up-time", f"conversion started {self.ready_at - self.t} ns "
                           f"before the part is powered up (t_power_up {tm.t_power_up} ns)")
            self.ready_at = None
            self.valid = True
        ch = self.next_ch
        self.converting = ch
        if self.valid:
            code = self.code_of(ch)
            word = (ch << 12) | (code if self.coding else code ^ 0x800)
            self.conversions += 1
        else:
            word = self.garbage
        word ^= self.address_xor << 12
        if self.stuck_dout is not None:
            word = 0xFFFF if self.stuck_dout else 0
        self.out_word = word
        self.t_cs_fall = self.t

    def _advance(self) -> None:
        assert self.seq
        self.seq_pos = (self.seq_pos + 1) % len(self.seq)
        self.next_ch = self.seq[self.seq_pos]

    def _end(self, din: int) -> None:
        """CS rising edge after 16 falling edges: the DIN word takes effect."""
        if self.stuck_din is not None:
            din = 0xFFFF if self.stuck_din else 0
        self.frames.append(Frame(self.t_cs_fall, din, self.out_word, self.converting, self.valid))
        was_valid = self.valid
        if self.shadow_pending:
            self.shadow_pending = False
            chans = shadow_channels(din)
            if chans:
                self.seq, self.seq_pos, self.next_ch = chans, 0, chans[0]
            else:
                self.seq, self.next_ch = None, self.add
        elif din & 0x8000:
            cw = din >> 4
            pm = (cw >> 4) & 3
            if pm == 0:
                self._fail("invalid-power-mode", f"control word 0x{cw:03X} has PM1 PM0 = 00")
            seq, shadow, add = (cw >> 10) & 1, (cw >> 3) & 1, (cw >> 6) & 7
            self.add, self.range_bit, self.coding = add, (cw >> 1) & 1, cw & 1
            if seq and shadow:
                self.seq, self.seq_pos, self.next_ch = list(range(add + 1)), 0, 0
            elif seq:
                if self.seq:
                    self._advance()
                else:
                    self.next_ch = add
            else:
                self.seq, self.next_ch = None, add
                self.shadow_pending = bool(shadow)
            self.pm = pm
        elif self.seq:
            self._advance()
        # power, from this CS rising edge
        if self.pm == PM_NORMAL and not self.powered:
            self.powered = True
            self.ready_at = self.t + self.timing.t_power_up
        elif self.pm == PM_FULL or (self.pm == PM_AUTO and was_valid):
            self.powered = False  # full shutdown now; auto shutdown after a valid conversion

    # -- pins ----------------------------------------------------------------
    def delay_ns(self, ns: int) -> None:
        if ns < 0:
            raise InvalidArgument(f"delay_ns: negative delay {ns}")
        self.t += int(ns)

    def set_cs(self, level: int) -> None:
        level = 1 if level else 0
        if level == self.cs:
            return
        tm = self.timing
        if level == 0:
            self._begin()
            self.cs = 0
            self._log("CS", 0)
            self.n_fall, self.din_word = 0, 0
            self.t_fall = self.t_rise = None
            self._set_dout(self.out_word >> 15)
        else:
            if self.n_fall < 16:
                self._fail("cs-early", f"CS raised after {self.n_fall} SCLK falling edges of 16 "
                           "(the conversion is aborted)")
            assert self.t_fall is not None
            if self.t - self.t_fall < tm.t_cs_hold:
                self._fail("cs-hold", f"CS raised {self.t - self.t_fall} ns after the 16th falling "
                           f"edge (min {tm.t_cs_hold} ns)")
            self.cs = 1
            self._log("CS", 1)
            self._set_dout(HIGH_Z)
            self.t_cs_rise = self.t
            self._end(self.din_word)

    def set_sclk(self, level: int) -> None:
        level = 1 if level else 0
        if level == self.sclk:
            return
        tm = self.timing
        self.sclk = level
        if self.cs:  # SCLK is ignored while CS is high
            self._log("SCLK", level)
            return
        if level == 1:
            self.t_rise = self.t
            self._log("SCLK", 1)
            return
        self.n_fall += 1
        if self.n_fall > 16:
            self._fail("clock-count", f"SCLK falling edge {self.n_fall} in a 16-clock frame")
        if self.n_fall == 1:
            if self.t - self.t_cs_fall < tm.t_cs_sclk:
                self._fail("cs-setup", f"first SCLK falling edge {self.t - self.t_cs_fall} ns after "
                           f"CS fell (min {tm.t_cs_sclk} ns)")
        else:
            assert self.t_fall is not None and self.t_rise is not None
            period = self.t - self.t_fall
            high, low = self.t - self.t_rise, self.t_rise - self.t_fall
            if period < tm.t_sclk_period or 5 * high < 2 * period or 5 * low < 2 * period:
                self._fail("clock-too-fast", f"SCLK period {period} ns (low {low}, high {high}; "
                           f"min {tm.t_sclk_period} ns, each phase >= 40 %)")
            if period > tm.t_sclk_period_max:
                self._fail("clock-too-slow", f"SCLK period {period} ns (max {tm.t_sclk_period_max} "
                           "ns: f_SCLK >= 10 kHz)")
        if self.t - self.t_din < tm.t_din_setup:
            self._fail("din-setup", f"DIN changed {self.t - self.t_din} ns before the falling edge "
                       f"(min {tm.t_din_setup} ns)")
        bit = self.din if self.stuck_din is None else self.stuck_din
        self.din_word = ((self.din_word << 1) | bit) & 0xFFFF
        self.t_fall = self.t
        self._log("SCLK", 0)
        if self.n_fall >= 16:
            self._set_dout(HIGH_Z)
        else:
            self._set_dout((self.out_word >> (15 - self.n_fall)) & 1)

    def set_din(self, level: int) -> None:
        level = 1 if level else 0
        if level == self.din:
            return
        if not self.cs and self.t_fall is not None and self.t - self.t_fall < self.timing.t_din_hold:
            self._fail("din-hold", f"DIN changed {self.t - self.t_fall} ns after the falling edge "
                       f"(min {self.timing.t_din_hold} ns)")
        self.din = level
        self.t_din = self.t
        self._log("DIN", level)

    def get_dout(self) -> int:
        tm = self.timing
        if self.cs or self.n_fall >= 16:
            self._fail("dout-three-state", "DOUT read while it is three-state "
                       + ("(CS high)" if self.cs else "(after the 16th falling edge)"))
        if self.n_fall == 0:
            if self.t - self.t_cs_fall < tm.t_dout_enable:
                self._fail("dout-early", f"DOUT read {self.t - self.t_cs_fall} ns after CS fell "
                           f"(valid after {tm.t_dout_enable} ns)")
        else:
            assert self.t_fall is not None
            if self.t - self.t_fall < tm.t_dout_access:
                self._fail("dout-early", f"DOUT read {self.t - self.t_fall} ns after an SCLK falling "
                           f"edge (next bit valid after {tm.t_dout_access} ns)")
        v = self.dout_level
        self._log("DOUT?", v)
        return v

    # -- frames ---------------------------------------------------------------
    def transfer(self, tx: Sequence[int], hold_ns: int = 50) -> list[int]:
        """Frame-level access (a hardware SPI controller): one 16-bit frame per
        word of ``tx`` at ``sclk_period_ns``, CS high ``t_quiet`` between frames
        and ``max(hold_ns, t_quiet)`` after the last; returns the DOUT words."""
        if not self.cs:
            raise InvalidArgument("transfer: CS is low (a pin-level frame is in progress)")
        out = []
        for i, w in enumerate(tx):
            self._begin()
            self.t += 16 * self.sclk_period_ns
            self.t_cs_rise = self.t
            out.append(self.out_word)
            self._end(int(w) & 0xFFFF)
            last = i + 1 == len(tx)
            self.t += max(int(hold_ns), self.timing.t_quiet) if last else self.timing.t_quiet
        return out
