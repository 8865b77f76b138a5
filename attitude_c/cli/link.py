"""``attitude link-rx``, ``link-tx`` and ``link-test``: the serial link of the
paper on real ports (any pyserial URL or device) and in simulation."""

from __future__ import annotations

import argparse
import json
import math
import sys
import threading
from collections.abc import Iterator
from types import SimpleNamespace
from typing import Any, Callable

from ..errors import AttitudeError
from . import options
from .options import integer, positive
from .stopping import GRACE_S, LineWriter, Stop


def _hex_block(b: bytes) -> str:
    return b.hex(" ")


def _parse_hex_line(line: str, n: int, lineno: int) -> bytes:
    text = line.replace(" ", "").replace(",", "").strip()
    try:
        blk = bytes.fromhex(text)
    except ValueError as exc:
        raise ValueError(f"stdin line {lineno}: not hex: {line.strip()!r}") from exc
    if len(blk) != n:
        raise ValueError(f"stdin line {lineno}: {len(blk)} bytes, block size is {n}")
    return blk


def test_samples(count: int | None, block_size: int = 6) -> Iterator[bytes]:
    """Test blocks: X, Y, Z as 12-bit ADC codes (TLC2543 range) in 16-bit
    big-endian words, slow sines around mid-scale; padded/truncated to the
    block size."""
    i = 0
    while count is None or i < count:
        words = [int(2048 + 1500 * math.sin(2 * math.pi * (i / 100.0 + k / 3.0))) for k in range(3)]
        raw = b"".join(w.to_bytes(2, "big") for w in words)
        yield (raw * (block_size // 6 + 1))[:block_size]
        i += 1


#: ``link-tx`` exit statuses (docs/link.md, "Commands").
EXIT_OK = 0
EXIT_PORT = 1  # the port cannot be opened or failed
EXIT_USAGE = 2  # bad argument or bad input line
EXIT_GAVE_UP = 3  # a block was given up after the receiver had answered (--on-give-up fail)
EXIT_NO_RECEIVER = 4  # no handshake from the receiver within --wait seconds
EXIT_INTERRUPTED = 130  # SIGINT / SIGTERM with a block in progress
#: ``link-rx``: stopped while stdout stayed blocked past the grace time (lines not printed, counted).
EXIT_RX_BLOCKED = 3
#: Seconds between two "waiting for the receiver" messages of link-tx.
WAIT_NOTE_S = 5.0


# numeric options (the shared validator, attitude_c/cli/options.py); ranges of csrc/include/attitude/link.h
BAUD = integer("--baud", 50, 4_000_000)
BLOCK_SIZE = integer("--block-size", 1, 64)
TICKS_MS = (1, 32767)  # link timeouts: 1..32767 ticks of 1 ms


def _add_common(p: argparse.ArgumentParser, auto: bool = False) -> None:
    p.add_argument("--port", required=True, help="device or pyserial URL (/dev/ttyS1, socket://host:port, ...)")
    p.add_argument("--baud", type=BAUD, default=9600, help="line rate (default 9600, 8N1)")
    p.add_argument("--block-size", type=BLOCK_SIZE, default=6, help="data bytes per block N (1..64, default 6)")
    p.add_argument("--impl", choices=("c", "python"), default="c", help="protocol end: the C machine or the Python one")
    _add_protocol(p, auto)


def _add_protocol(p: argparse.ArgumentParser, auto: bool = False) -> None:
    p.add_argument("--protocol", choices=("legacy", "v2", "auto") if auto else ("legacy", "v2"), default="legacy",
                   help="legacy: the paper's AA/BB handshake (default); v2: the streaming protocol "
                        "(CRC-32C, windowed acknowledgements; 6-byte records, --block-size ignored)"
                        + ("; auto: whichever the sender speaks (the first valid v2 frame or legacy block "
                           "whose records decode names it, and is answered: nothing lost)" if auto else ""))


def register(sub: Any) -> None:
    p = sub.add_parser("link-rx", help="receiver B on a serial port: print accepted blocks as hex")
    _add_common(p, auto=True)
    p.add_argument("--count", type=integer("--count", 1), default=None, help="stop after N accepted blocks")
    p.add_argument("--gap-timeout-ms", type=integer("--gap-timeout-ms", *TICKS_MS), default=20,
                   help="max gap inside a block (ms, 1..32767)")
    p.add_argument("--idle-eof", type=positive("--idle-eof"), default=None, metavar="S",
                   help="treat this many seconds without a byte as end of input")
    p.add_argument("--duration", type=positive("--duration"), default=None, metavar="S",
                   help="stop after this many seconds")
    p.add_argument("--decode", action="store_true",
                   help="print each 6-byte record decoded with the block format (attitude/block.h) as a "
                        "JSON line: samples numbered, reports, records that break the format")
    p.set_defaults(func=cmd_rx)

    p = sub.add_parser("link-tx", help="sender A on a serial port: blocks from stdin hex lines or test samples")
    _add_common(p)
    p.add_argument("--count", type=integer("--count", 1), default=None, help="send at most N blocks")
    p.add_argument("--generate", action="store_true", help="send generated test samples instead of stdin")
    p.add_argument("--syn-timeout-ms", type=integer("--syn-timeout-ms", *TICKS_MS), default=50,
                   help="ms to wait for 0xBB after 0xAA (1..32767, default 50)")
    p.add_argument("--answer-timeout-ms", type=integer("--answer-timeout-ms", *TICKS_MS), default=50,
                   help="ms to wait for the answer after the checksum (1..32767, default 50)")
    p.add_argument("--max-attempts", type=integer("--max-attempts", 1, 255), default=5,
                   help="attempts per block (1..255, default 5)")
    p.add_argument("--wait", type=options.nonneg("--wait"), default=None, metavar="S",
                   help="wait at most S seconds for the receiver's first handshake (default: for ever, "
                   f"with a message every {WAIT_NOTE_S:g} s; 0: no wait)")
    p.add_argument("--on-give-up", choices=("fail", "skip"), default="fail",
                   help="a block given up after the receiver has answered: fail (default) ends the "
                   f"command with exit status {EXIT_GAVE_UP}, naming the block; skip goes on with the next")
    p.set_defaults(func=cmd_tx)

    p = sub.add_parser("link-test", help="N blocks through a pair of ends and a (bad) channel; print statistics")
    p.add_argument("--blocks", type=integer("--blocks", 1, 10_000_000), default=1000,
                   help="number of blocks (default 1000)")
    p.add_argument("--block-size", type=BLOCK_SIZE, default=6)
    p.add_argument("--sender", choices=("c", "python"), default="c")
    p.add_argument("--receiver", choices=("c", "python"), default="c")
    p.add_argument("--transport", choices=("sim", "pty", "socket"), default="sim",
                   help="sim: simulated line time (default); pty / socket: real time over a bridge")
    p.add_argument("--baud", type=BAUD, default=9600)
    p.add_argument("--ber", type=options.probability("--ber", 0.5), default=0.0, help="bit error rate per data bit")
    p.add_argument("--drop", type=options.probability("--drop"), default=0.0, help="probability a byte is lost")
    p.add_argument("--insert", type=options.probability("--insert"), default=0.0,
                   help="probability a garbage byte is inserted")
    p.add_argument("--duplicate", type=options.probability("--duplicate"), default=0.0,
                   help="probability a byte arrives twice")
    p.add_argument("--dead", action="append", default=[], metavar="START:LENGTH",
                   help="line dead from START for LENGTH seconds (repeatable, at most 4)")
    p.add_argument("--reboot", action="append", default=[], metavar="TIME:sender|receiver",
                   help="that end reboots at TIME seconds (sim only, repeatable)")
    p.add_argument("--seed", type=integer("--seed", 0, 2**63 - 1), default=1)
    p.add_argument("--json", action="store_true", help="print the statistics as JSON")
    _add_protocol(p)
    p.set_defaults(func=cmd_test)


def _block_printer(write: Callable[[str], None] = print) -> Any:
    """``show(block)`` writing each record of a block as one JSON line with ``write``
    (libattitude's block decoder and sequence tracker through attitude_c.link.block)."""
    from ..link import block

    tracker = block.SeqTracker()
    size = block.fmt().size

    def show(b: bytes) -> None:
        for k in range(0, len(b), size):
            raw = b[k:k + size]
            rec, span, st = tracker.decode(raw)  # a slip shows in the loss report's "slip"
            if rec is None or span is None:  # no place in the numbering
                write(json.dumps({"error": tracker.error(st), "raw": raw.hex()}))
                continue
            out: dict[str, Any]
            if rec.kind == "sample":
                out = {"n": span.first, "codes": list(rec.codes)}
                if span.part != "gyr":  # an aided stream's accelerometer or magnetometer record
                    out["part"] = span.part
                if st != 0:
                    out["error"] = tracker.error(st)  # never a sample to integrate
            else:
                out = rec.as_dict()
                if rec.is_loss:
                    out.update(first=span.first, count=span.count, slip=span.slip)
            write(json.dumps(out))

    return show


def _open(cmd: str, args: argparse.Namespace) -> Any:
    """The port of ``--port`` at ``--baud``; None when it does not open (said in one line)."""
    from ..link.transport import open_port

    try:
        return open_port(args.port, args.baud)
    except AttitudeError as exc:
        print(f"{cmd}: {exc}", file=sys.stderr)
        return None


def _receive(args: argparse.Namespace, port: Any, protocol: str, show: Callable[[bytes], None],
             stop: threading.Event, *, count: int | None, duration: float | None, receiver: Any = None) -> Any:
    """link-rx: the receiver of ``protocol`` (legacy or v2) on ``port``, printing with ``show``,
    until ``count``, ``duration``, --idle-eof or a stop; ``receiver``: one to go on with
    (--protocol auto's). Its report."""
    from ..link.transport import run_receiver
    from ..link.transport2 import run_receiver2

    common: dict[str, Any] = {"count": count, "duration": duration, "stop": stop, "eof_after": args.idle_eof,
                              "receiver": receiver}
    if protocol == "v2":
        return run_receiver2(port, impl=args.impl, on_record=show, keep_records=False, **common)
    return run_receiver(port, impl=args.impl, block_size=args.block_size, gap_timeout_ms=args.gap_timeout_ms,
                        on_block=show, keep_blocks=False, **common)


def cmd_rx(args: argparse.Namespace) -> int:
    if args.protocol != "v2" and (args.decode or args.protocol == "auto"):
        from ..link import block

        if args.block_size % block.fmt().size:
            what = "--decode" if args.decode else "--protocol auto"
            print(f"link-rx: {what} needs a block size that is a multiple of {block.fmt().size} (records "
                  f"of the block format), got {args.block_size}", file=sys.stderr)
            return 2
    stopping = Stop()
    stop = stopping.event
    port = _open("link-rx", args)
    if port is None:
        return 1
    out = LineWriter(stopping)  # a stop does not wait for a blocked stdout
    show: Callable[[bytes], None] = _block_printer(out.write) if args.decode \
        else (lambda b: out.write(_hex_block(b)))
    what = (f"link v2, {args.impl}" if args.protocol == "v2" else f"N={args.block_size}, {args.impl}"
            + (", legacy or link v2" if args.protocol == "auto" else ""))
    print(f"link-rx: listening on {args.port} ({args.baud} 8N1, {what})", file=sys.stderr, flush=True)
    try:
        if args.protocol == "auto":
            rep = _rx_auto(args, port, show, stop)
        else:
            rep = _receive(args, port, args.protocol, show, stop, count=args.count, duration=args.duration)
    except AttitudeError as exc:
        print(f"link-rx: {exc}", file=sys.stderr)
        return 2
    finally:
        port.close()
    stats = {**rep.stats, "lines_lost": out.lost} if out.lost else rep.stats
    print("link-rx stats: " + json.dumps(stats) + f" (ended by {rep.ended_by})", file=sys.stderr)
    if rep.error:
        print(f"link-rx: {rep.error}", file=sys.stderr)
        return 1
    if out.lost:
        print(f"link-rx: stopped with stdout blocked for {GRACE_S:g} s: {out.lost} line(s) of accepted "
              "data not printed (lines_lost)", file=sys.stderr)
        return EXIT_RX_BLOCKED
    return 0


def _tx_input(args: argparse.Namespace, size: int) -> Iterator[bytes]:
    """What link-tx sends: ``--generate``d test samples, or hex lines from stdin (blank and
    ``#`` lines skipped), at most ``--count``, each ``size`` bytes."""
    if args.generate:
        yield from test_samples(args.count if args.count is not None else 100, size)
        return
    k = 0
    for lineno, line in enumerate(sys.stdin, 1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        if args.count is not None and k >= args.count:
            return
        yield _parse_hex_line(line, size, lineno)
        k += 1


def cmd_tx(args: argparse.Namespace) -> int:
    from ..link.transport import OUTCOME_INTERRUPTED, OUTCOME_NO_RECEIVER, BlockReport, run_sender

    v2 = args.protocol == "v2"
    stop = Stop().event
    blocks = _tx_input(args, 6 if v2 else args.block_size)  # link v2: 6-byte records
    port = _open("link-tx", args)
    if port is None:
        return EXIT_PORT

    def show(r: BlockReport) -> None:
        if r.outcome in (OUTCOME_NO_RECEIVER, OUTCOME_INTERRUPTED):
            return  # said on stderr below
        print(f"block {r.index} {_hex_block(r.block)}: {r.outcome} after {r.attempts} attempt(s)"
              f" (naks {r.naks}, timeouts {r.timeouts})", flush=True)

    def waiting(seconds: float) -> None:
        print(f"link-tx: waiting for the receiver on {args.port} ({seconds:.0f} s, block 0 not sent yet)",
              file=sys.stderr, flush=True)

    try:
        if v2:
            from ..link.transport2 import run_sender2

            rep2 = run_sender2(port, blocks, impl=args.impl, timeout=args.wait, stop=stop)
        else:
            reports, stats = run_sender(port, blocks, impl=args.impl, block_size=args.block_size,
                                        syn_timeout_ms=args.syn_timeout_ms,
                                        answer_timeout_ms=args.answer_timeout_ms,
                                        max_attempts=args.max_attempts, on_result=show, stop=stop,
                                        wait_first=args.wait, on_waiting=waiting, waiting_every=WAIT_NOTE_S,
                                        on_give_up=args.on_give_up)
    except ValueError as exc:
        print(f"link-tx: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except AttitudeError as exc:
        print(f"link-tx: {exc}", file=sys.stderr)
        return EXIT_PORT
    finally:
        port.close()
    return _tx2_end(args, rep2) if v2 else _tx_end(args, reports, stats)


def _tx_end(args: argparse.Namespace, reports: list[Any], stats: dict[str, int]) -> int:
    """link-tx (legacy): the statistics, the last block's fate, the exit status."""
    from ..link.transport import OUTCOME_GAVE_UP, OUTCOME_INTERRUPTED, OUTCOME_NO_RECEIVER

    print("link-tx stats: " + json.dumps(stats), file=sys.stderr)
    last = reports[-1] if reports else None
    if last is not None and last.outcome == OUTCOME_NO_RECEIVER:
        print(f"link-tx: no handshake from the receiver in {args.wait:g} s: block {last.index} "
              "and the rest not sent", file=sys.stderr)
        return EXIT_NO_RECEIVER
    if last is not None and last.outcome == OUTCOME_INTERRUPTED:
        print(f"link-tx: interrupted: block {last.index} and the rest not sent", file=sys.stderr)
        return EXIT_INTERRUPTED
    if args.on_give_up == "fail" and last is not None and last.outcome == OUTCOME_GAVE_UP:
        print(f"link-tx: gave up on block {last.index} ({_hex_block(last.block)}) after {last.attempts} "
              "attempt(s); the blocks after it were not sent (--on-give-up skip goes on instead)",
              file=sys.stderr)
        return EXIT_GAVE_UP
    skipped = [r.index for r in reports if r.outcome == OUTCOME_GAVE_UP]
    if skipped:
        print(f"link-tx: skipped {len(skipped)} block(s) given up: {', '.join(map(str, skipped))}",
              file=sys.stderr)
    return EXIT_OK


# repeatable pair options of link-test (checked in cmd_test, after the others)
_DEAD = options.pair("--dead", options.nonneg("--dead START"), positive("--dead LENGTH"), "START:LENGTH")
_REBOOT = options.pair("--reboot", options.nonneg("--reboot TIME"),
                       options.choice("--reboot", ("sender", "receiver")), "TIME:sender|receiver")


def cmd_test(args: argparse.Namespace) -> int:
    import numpy as np

    from ..link.sim import ChannelConfig, simulate_link

    try:
        dead = [_DEAD(d) for d in args.dead]
        reboots: list[Any] = [_REBOOT(r) for r in args.reboot]
        chan = ChannelConfig(ber=args.ber, drop=args.drop, insert=args.insert, duplicate=args.duplicate,
                             dead=dead, seed=args.seed)  # type: ignore[arg-type]
        blocks = np.frombuffer(b"".join(test_samples(args.blocks, args.block_size)),
                               dtype=np.uint8).reshape(args.blocks, args.block_size)
        if reboots and args.transport != "sim":
            raise ValueError("--reboot is only available with --transport sim")
        if args.protocol == "v2":
            out = _test2(args, chan, reboots, [bytes(r) for r in blocks])
        elif args.transport == "sim":
            run = simulate_link(blocks, channel=chan, sender=args.sender, receiver=args.receiver,
                                baud=args.baud, reboots=reboots)
            out = run.summary()
            out["channel"] = run.channel_stats
            out["engine"] = run.engine
        else:
            out = _real_time_test(args, chan, [bytes(r) for r in blocks])
    except (ValueError, TypeError, argparse.ArgumentTypeError) as exc:
        print(f"link-test: {exc}", file=sys.stderr)
        return 2
    except AttitudeError as exc:
        print(f"link-test: {exc}", file=sys.stderr)
        return 1
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        for k, v in out.items():
            print(f"{k:>18}: {v}")
    return 0


def _over_bridge(args: argparse.Namespace, chan: Any, receive: Callable[[Any, threading.Event], Any],
                 send: Callable[[Any], Any]) -> tuple[Any, Any, float, Any]:
    """link-test --transport pty|socket: ``receive(port, stop)`` in a thread on one end of a real
    bridge through ``chan``, ``send(port)`` on the other. Returns the receiver's report (None if it
    did not end), the sender's, the seconds ``send`` took and the channel's statistics."""
    import time

    from ..link.transport import PtyPair, SocketRelay, open_port

    bridge: Any = PtyPair(baud=args.baud, channel=chan) if args.transport == "pty" \
        else SocketRelay(baud=args.baud, channel=chan)
    urls = bridge.paths if args.transport == "pty" else [bridge.url, bridge.url]
    stop = threading.Event()
    box: dict[str, Any] = {}
    try:
        pb = open_port(urls[1], args.baud)
        th = threading.Thread(target=lambda: box.setdefault("rx", receive(pb, stop)), daemon=True)
        th.start()
        pa = open_port(urls[0], args.baud)
        t0 = time.monotonic()
        sent = send(pa)
        dt = time.monotonic() - t0
        time.sleep(0.1)
        stop.set()
        th.join(timeout=5)
        pa.close()
        pb.close()
    finally:
        bridge.close()
    return box.get("rx"), sent, dt, bridge.channel_stats()


def _real_time_test(args: argparse.Namespace, chan: Any, blocks: list[bytes]) -> dict[str, Any]:
    from ..link.transport import run_receiver, run_sender

    rx, (reports, sstats), dt, channel = _over_bridge(
        args, chan, lambda port, stop: run_receiver(port, impl=args.receiver, block_size=args.block_size, stop=stop),
        lambda port: run_sender(port, blocks, impl=args.sender, block_size=args.block_size))
    got = rx.blocks if rx is not None else []
    sent = set(blocks)
    acked = sum(r.outcome == "accepted" for r in reports)
    return {
        "blocks": len(blocks),
        "accepted_by_B": len(got),
        "acked": acked,
        "gave_up": sum(r.outcome == "gave up" for r in reports),
        "not_sent_blocks_accepted": sum(b not in sent for b in got),
        "duration_s": dt,
        "blocks_per_s": acked / dt if dt > 0 else 0.0,
        "sender": sstats,
        "receiver": rx.stats if rx is not None else {},
        "channel": channel,
    }


# ---------------------------------------------------------------- link v2 (docs/link.md, "Link v2")

def _rx_auto(args: argparse.Namespace, port: Any, show: Callable[[bytes], None], stop: threading.Event) -> Any:
    """link-rx --protocol auto: listen_auto, then the receiver of the protocol heard; its report."""
    import time

    from ..link.transport2 import listen_auto

    t0 = time.monotonic()

    def left() -> float | None:
        return None if args.duration is None else max(1e-3, args.duration - (time.monotonic() - t0))

    heard = listen_auto(port, impl=args.impl, block_size=args.block_size, gap_timeout_ms=args.gap_timeout_ms,
                        on_block=show, on_record=show, stop=stop, duration=args.duration,
                        eof_after=args.idle_eof)
    if heard.protocol == "legacy":
        print("link-rx: the sender speaks the legacy protocol", file=sys.stderr, flush=True)
        rep: Any = _receive(args, heard.port, "legacy", show, stop, receiver=heard.legacy, count=args.count,
                            duration=left())
    elif heard.protocol == "v2":
        print("link-rx: the sender speaks link v2", file=sys.stderr, flush=True)
        count = None if args.count is None else args.count - heard.records
        if count is not None and count <= 0:
            rep = SimpleNamespace(stats=heard.v2.stats.as_dict(), ended_by="count", error="")
        else:
            rep = _receive(args, heard.port, "v2", show, stop, receiver=heard.v2, count=count, duration=left())
    else:
        rep = SimpleNamespace(stats={"legacy": heard.legacy.stats.as_dict(), "v2": heard.v2.stats.as_dict()},
                              ended_by=heard.ended_by + ", no protocol heard", error=heard.error)
    return rep


def _tx2_end(args: argparse.Namespace, rep: Any) -> int:
    """link-tx --protocol v2: the statistics, what was acknowledged, the exit status."""
    print("link-tx stats: " + json.dumps(rep.stats), file=sys.stderr)
    print(f"link-tx: {rep.acknowledged} of {rep.pushed} record(s) acknowledged (ended by {rep.ended_by})",
          flush=True)
    if rep.ended_by == "error":
        print(f"link-tx: {rep.error}", file=sys.stderr)
        return EXIT_PORT
    if rep.ended_by == "stop":
        return EXIT_INTERRUPTED
    if rep.ended_by == "timeout":
        print(f"link-tx: {rep.pushed - rep.acknowledged} record(s) not acknowledged within --wait "
              f"{args.wait:g} s", file=sys.stderr)
        return EXIT_NO_RECEIVER
    return EXIT_OK


def _test2(args: argparse.Namespace, chan: Any, reboots: list[Any], records: list[bytes]) -> dict[str, Any]:
    from ..link.sim2 import simulate_link2
    from ..link.transport2 import run_receiver2, run_sender2

    if args.transport == "sim":
        when = {"sender": 0.0, "receiver": 0.0}
        for t, who in reboots:
            if who not in when or when[who]:
                raise ValueError("--protocol v2: at most one --reboot per end, TIME:sender|receiver")
            when[who] = t
        python = "python" in (args.sender, args.receiver)
        run = simulate_link2(args.blocks, chan, baud=args.baud, engine="python" if python else "c",
                             sender=args.sender, receiver=args.receiver, reboot_sender_s=when["sender"],
                             reboot_receiver_s=when["receiver"])
        return {"protocol": "v2", **run.summary(), "channel": run.channel}
    rx, rep, dt, channel = _over_bridge(
        args, chan, lambda port, stop: run_receiver2(port, impl=args.receiver, stop=stop),
        lambda port: run_sender2(port, records, impl=args.sender, timeout=600))
    got = rx.records if rx is not None else []
    return {"protocol": "v2", "records": len(records), "acknowledged": rep.acknowledged,
            "delivered": len(got), "in_order_exactly_once": got == records[:len(got)],
            "duration_s": dt, "records_per_s": rep.acknowledged / dt if dt > 0 else 0.0,
            "sender": rep.stats, "receiver": rx.stats if rx is not None else {}, "channel": channel}
