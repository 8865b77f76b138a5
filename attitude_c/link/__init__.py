"""Serial link of the paper (sec. 3.3): both ends in C and Python, a channel
simulator, pyserial transports. See docs/link.md.

- :class:`Sender` / :class:`Receiver`: the protocol written in Python from the spec;
- :class:`CSender` / :class:`CReceiver`: the C machines (attitude/link.h) via CFFI;
- :func:`simulate_link` + :class:`ChannelConfig`: blocks through A -> bad line -> B
  in simulated 9600-baud time (fast all-C path, or any pair of ends);
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
    "CSender",
    "Channel",
    "ChannelConfig",
    "LinkBusy",
    "LinkRun",
    "Receiver",
    "ReceiverStats",
    "Result",
    "Sender",
    "SenderStats",
    "checksum",
    "make_receiver",
    "make_sender",
    "simulate_link",
]
