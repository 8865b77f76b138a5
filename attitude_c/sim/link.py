"""Stage 6 of the simulator (docs/architecture.md): the serial link.

The board's records, one 6-byte link block each, through the paper's
AA/BB handshake protocol (docs/link.md): the C sender A, the C channel
simulator (``ber``: independent bit errors on both directions) and the C
receiver B, in simulated 9600-baud time (:func:`attitude_c.link.simulate_link`,
all C). ``kind="none"`` hands the records over directly. The header reports
(BOOT, OVERSAMPLE) cross the same ends on a clean line: the channel's errors
start with the first sample, so a run's samples meet the same errors whatever
the header (a seed gives the same draws as it always has). A second link
protocol is another ``kind`` of this stage.

The simulator knows which sent record each delivered one came from
(:attr:`Delivered.source`): the chain judges the attitude at the true time
of every delivered sample, and the summary says exactly which samples were
lost, duplicated or corrupted without detection.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from ..errors import InvalidArgument
from ..link import ChannelConfig, simulate_link
from .board import BoardStream

__all__ = ["Delivered", "Link", "LinkKind"]

LinkKind = Literal["c", "none"]


@dataclass
class Delivered:
    """What the host's receiver accepted: ``records`` in order; ``source[j]`` the
    index in the sent stream of the record delivered j-th (the simulator's ground
    truth; None when only the stream's own numbering is known, e.g. the
    firmware in s51); ``stats`` the link's accounting (JSON-ready)."""

    records: list[bytes]
    source: np.ndarray | None
    stats: dict[str, Any] = field(default_factory=dict)


def _run(blocks: list[bytes], ber: float, seed: int, attempts: int) -> tuple[list[bytes], np.ndarray, dict[str, Any]]:
    """Blocks through the C sender → channel simulator → C receiver."""
    arr = np.frombuffer(b"".join(blocks), dtype=np.uint8).reshape(len(blocks), -1)
    run = simulate_link(arr, channel=ChannelConfig(ber=ber, seed=seed), max_attempts=attempts)
    correct = np.asarray(run.correct, dtype=bool)
    dup = np.asarray(run.duplicate, dtype=bool)
    idx = np.asarray(run.accepted_index, dtype=np.int64).copy()
    # a block B accepted while A was sending none (index -1) sits after the previous one
    for j in range(len(idx)):
        if idx[j] < 0:
            idx[j] = min(len(blocks) - 1, (idx[j - 1] + 1) if j else 0)
    delivered = [bytes(r) for r in np.asarray(run.accepted, dtype=np.uint8)]
    s = run.summary()
    counts = {
        "delivered_ok": int(np.count_nonzero(correct & ~dup)),
        "duplicated": int(np.count_nonzero(dup)),
        "corrupted_undetected": int(np.count_nonzero(~correct)),
        # never accepted intact (A may give up on a block B did accept: 0x00 lost)
        "lost": len(blocks) - len(np.unique(idx[correct])),
        "gave_up": int(s["gave_up"]),
        "link_time_s": float(s["duration_s"]),
        "sender": s["sender"],
        "receiver": s["receiver"],
    }
    return delivered, idx, counts


@dataclass(frozen=True)
class Link:
    """The link stage: ``kind`` "c" (the C ends and the channel simulator) or "none";
    ``ber`` the channel's bit error rate; ``attempts`` per block before A gives up."""

    kind: LinkKind = "c"
    ber: float = 0.0
    attempts: int = 5

    def carry(self, stream: BoardStream, rng: np.random.Generator, period: float) -> Delivered:
        """Send ``stream`` (one block per record); ``rng`` seeds the channel.

        Statistics count the samples (the header reports are not samples):
        ``sent``, ``delivered`` (sample records accepted), ``delivered_ok``
        (intact), ``duplicated`` (accepted twice: B's 0x00 lost, A resent),
        ``corrupted_undetected`` (accepted with errors the 8-bit sum missed),
        ``lost`` (never accepted intact: A gave up)."""
        h = stream.header
        head, samples = stream.records[:h], stream.records[h:]
        if self.kind == "none":
            n = len(samples)
            return Delivered(list(stream.records), np.arange(len(stream.records)),
                             {"link": "none", "sent": n, "delivered": n, "lost": 0, "duplicated": 0,
                              "corrupted_undetected": 0})
        if self.kind != "c":
            raise InvalidArgument(f"link must be 'c' or 'none', got {self.kind!r}")
        seed = int(rng.integers(1, 2**31 - 1))
        out: dict[str, Any] = {"link": "c", "ber": self.ber, "sent": len(samples), "seed": seed,
                               "backend": "c (attitude_c.link.simulate_link: C sender, channel, C receiver)"}
        got_head, idx_head, _ = _run(head, 0.0, seed, self.attempts)
        got, idx, counts = _run(samples, self.ber, seed, self.attempts) if samples else ([], np.zeros(0, int), {})
        out["delivered"] = len(got)
        out.update(counts)
        if "link_time_s" in out and samples:
            # the simulated line carries the blocks back to back: the fraction of
            # the run's real time the 9600-baud exchanges need (must stay below 1)
            out["line_busy_fraction"] = out["link_time_s"] / (len(samples) * period)
        return Delivered(got_head + got, np.concatenate([idx_head, idx + h]), out)
