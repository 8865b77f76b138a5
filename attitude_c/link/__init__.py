"""Serial link of the paper (sec. 3.3): both ends in C and Python, a channel
simulator, pyserial transports. See docs/link.md.

- :class:`Sender` / :class:`Receiver`: the protocol written in Python from the spec;
- :class:`CSender` / :class:`CReceiver`: the C machines (attitude/link.h) via CFFI;
- :func:`simulate_link` + :class:`ChannelConfig`: blocks through A -> bad line -> B
  in simulated 9600-baud time (fast all-C path, or any pair of ends);
- link v2 (the hardened streaming protocol): :class:`Sender2` / :class:`Receiver2`
  from the spec, :class:`CSender2` / :class:`CReceiver2` the C machines,
  :func:`simulate_link2`;
- :mod:`attitude_c.link.transport`: pyserial ports, pty pairs, a socket relay,
  and real-time loops running either end on a port.
"""

from .cends import CReceiver, CSender, make_receiver, make_sender
from .protocol import (
    ACK,
    NAK,
    SYN,
    SYN_ACK,
    LinkBusy,
    Receiver,
    ReceiverStats,
    Result,
    Sender,
    SenderStats,
    checksum,
)
from .sim import (
    OUTCOME_ACKED,
    OUTCOME_GAVE_UP,
    OUTCOME_LOST_REBOOT,
    OUTCOME_PENDING,
    Channel,
    ChannelConfig,
    LinkRun,
    simulate_link,
)
from .sim2 import simulate_link2
from .v2 import Receiver2, Result2, Sender2
from .v2c import CReceiver2, CSender2, Link2Run

__all__ = [
    "ACK",
    "NAK",
    "OUTCOME_ACKED",
    "OUTCOME_GAVE_UP",
    "OUTCOME_LOST_REBOOT",
    "OUTCOME_PENDING",
    "SYN",
    "SYN_ACK",
    "CReceiver",
    "CReceiver2",
    "CSender",
    "CSender2",
    "Channel",
    "ChannelConfig",
    "Link2Run",
    "LinkBusy",
    "LinkRun",
    "Receiver",
    "Receiver2",
    "ReceiverStats",
    "Result",
    "Result2",
    "Sender",
    "Sender2",
    "SenderStats",
    "checksum",
    "make_receiver",
    "make_sender",
    "simulate_link",
    "simulate_link2",
]
