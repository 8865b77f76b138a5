"""Adapter: board words through the C link sender and receiver (attitude_c.link).

Each sample (three 16-bit words X, Y, Z) becomes one 6-byte block, big
endian, as the link protocol's default block. The delivered blocks are
matched back to the sent ones so that the summary can say exactly which
samples were lost, duplicated or corrupted without detection.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from ..errors import InvalidArgument

# how far ahead a delivered block is searched among the sent ones (a run of
# this many consecutive lost blocks would be counted as one corruption)
_LOOKAHEAD = 64


def words_to_blocks(words: np.ndarray) -> list[bytes]:
    w = np.asarray(words)
    if np.any(w < 0) or np.any(w > 0xFFFF):
        raise InvalidArgument("board words must fit 16 bits")
    return [bytes(row) for row in w.astype(">u2").view(np.uint8).reshape(len(w), -1)]


def blocks_to_words(blocks: list[bytes]) -> np.ndarray:
    if not blocks:
        return np.zeros((0, 3), dtype=np.int64)
    a = np.frombuffer(b"".join(blocks), dtype=">u2").reshape(len(blocks), 3)
    return a.astype(np.int64)


def align(sent: list[bytes], delivered: list[bytes]) -> tuple[np.ndarray, dict[str, int]]:
    """Sample index of each delivered block and the loss accounting.

    A delivered block equal to the next expected sent block is delivered;
    equal to the previous one, a duplicate (B's 0x00 lost, A resent);
    equal to a later one, the blocks in between were lost; equal to none
    within the lookahead, a corrupted block B accepted (8-bit checksum miss).
    """
    idx = np.empty(len(delivered), dtype=np.int64)
    p = 0
    counts = {"delivered_ok": 0, "duplicated": 0, "corrupted_undetected": 0, "lost": 0}
    for j, d in enumerate(delivered):
        if p < len(sent) and d == sent[p]:
            idx[j] = p
            p += 1
            counts["delivered_ok"] += 1
            continue
        if p > 0 and d == sent[p - 1]:
            idx[j] = p - 1
            counts["duplicated"] += 1
            continue
        hit = -1
        for q in range(p + 1, min(len(sent), p + 1 + _LOOKAHEAD)):
            if d == sent[q]:
                hit = q
                break
        if hit >= 0:
            counts["lost"] += hit - p
            idx[j] = hit
            p = hit + 1
            counts["delivered_ok"] += 1
        else:
            idx[j] = min(p, len(sent) - 1)
            p += 1
            counts["corrupted_undetected"] += 1
    counts["lost"] += max(0, len(sent) - p)
    return idx, counts


def _run_c_link(blocks: list[bytes], ber: float, seed: int, attempts: int
                ) -> tuple[list[bytes], np.ndarray, dict[str, Any]]:
    """Blocks through the C sender → channel simulator → C receiver in
    simulated 9600-baud time (attitude_c.link.simulate_link, all-C path)."""
    try:
        from ..link import ChannelConfig, simulate_link
    except ImportError as exc:
        raise ImportError(f"attitude_c.link is not available in this build ({exc})") from exc
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


def send_words(words: np.ndarray, *, ber: float, rng: np.random.Generator, attempts: int,
               period: float, progress: Callable[[str, int, int], None] | None = None
               ) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """Send (n, 3) words through the link; return (delivered words (m, 3),
    sample index of each (m,), statistics).

    Accounting: ``delivered_ok`` samples arrived intact, ``duplicated`` were
    accepted twice (B's 0x00 lost, A resent), ``corrupted_undetected`` were
    accepted with errors the 8-bit checksum missed, ``lost`` were never
    accepted (A gave up). The integrator gets exactly the delivered words.
    """
    blocks = words_to_blocks(words)
    seed = int(rng.integers(1, 2**31 - 1))
    out: dict[str, Any] = {"link": "c", "ber": ber, "sent": len(blocks), "seed": seed}
    try:
        delivered, idx, counts = _run_c_link(blocks, ber, seed, attempts)
        out["backend"] = "c (attitude_c.link.simulate_link: C sender, channel, C receiver)"
    except ImportError as exc:
        if ber > 0:
            raise InvalidArgument(f"ber > 0 needs the C link: {exc}") from exc
        delivered = list(blocks)
        idx, counts = align(blocks, delivered)
        out["backend"] = "direct (attitude_c.link not built)"
    out["delivered"] = len(delivered)
    out.update(counts)
    if "link_time_s" in out and len(blocks):
        # the simulated line carries the blocks back to back: the fraction of
        # the run's real time the 9600-baud exchanges need (must stay below 1)
        out["line_busy_fraction"] = out["link_time_s"] / (len(blocks) * period)
    return blocks_to_words(delivered), idx, out
