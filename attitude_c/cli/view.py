"""``attitude view``: live attitude in a web browser, from attitude-rx on
stdin, a serial port, a recording or the simulator (docs/view.md)."""

from __future__ import annotations

import argparse
import asyncio
import signal
import sys
from typing import Any

from ..errors import AttitudeError
from . import options
from .options import integer as _int_range
from .options import positive as _positive
from .options import triple as _triple

#: ``attitude view`` exit statuses (docs/view.md, "Exit statuses").
EXIT_OK = 0  # stopped with Ctrl-C / SIGTERM
EXIT_SOURCE = 1  # the source cannot be opened or read (file, port, simulation), or the recording failed
EXIT_USAGE = 2  # bad option
EXIT_SERVE = 3  # cannot serve: the address cannot be listened on, or aiohttp is missing

DEFAULT_PORT = 8765
#: --stall's largest value (s): a stream quiet for an hour is stalled whatever its rate.
STALL_MAX_S = 3600.0
#: --speed's range: a thousandth of real time to a thousand times it.
SPEED_RANGE = (1e-3, 1e3)


def register(sub: Any) -> None:
    from ..view.stream import DISPLAY_RATE_MAX, DISPLAY_RATE_MIN, HISTORY_MAX_S

    p = sub.add_parser(
        "view", help="live attitude display in a web browser (local web server)",
        description="Serve a page showing the attitude live: attitude and heading indicators, the body "
        "axes in 3D, strip charts of the angles and rates, the link's counters and the rate received. "
        "Every sample is recorded (download it from the page as CSV). The server listens on "
        "127.0.0.1 only, unless --bind says otherwise, and answers only to this machine's names "
        "(--allow-host adds others).",
        epilog="exit statuses: 0 stopped with Ctrl-C; 1 the source cannot be opened or read; 2 bad "
        "option; 3 cannot listen on the address (or aiohttp missing). See docs/view.md.")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--stdin", action="store_true",
                     help="read attitude-rx's output from standard input (--format jsonl, or CSV)")
    src.add_argument("--serial", metavar="PORT",
                     help="a serial device or pyserial URL (/dev/ttyUSB0, socket://host:port, ...): the "
                     "link's receiver B, the block decoder and an estimator run here")
    src.add_argument("--replay", metavar="FILE",
                     help="replay a recording: attitude-rx's JSON Lines or CSV, a view recording, attitude "
                     "simulate's timeseries.csv, or a BROAD trial (.mat, run through the estimator)")
    src.add_argument("--simulate", nargs=argparse.REMAINDER, metavar="SIMULATE_OPTIONS",
                     help="run the simulator with the truth drawn beside the estimate; every argument after "
                     "--simulate is an option of attitude simulate (so put it last), e.g. --simulate "
                     "--period 0.005 --duration 600")
    g = p.add_argument_group("server")
    g.add_argument("--bind", default="127.0.0.1", metavar="ADDRESS",
                   help="address to listen on (default 127.0.0.1; an address that is not loopback lets "
                   "other machines watch and download, with a warning)")
    g.add_argument("--allow-host", action="append", default=[], metavar="NAME",
                   help="also answer to this host name (repeatable; '*': to any name). By default the server "
                   "answers only to the loopback names, this machine's own names and addresses, and --bind "
                   "(a page of another site resolved to this machine gets nothing)")
    g.add_argument("--port", type=_int_range("--port", 0, 65535), default=DEFAULT_PORT,
                   help=f"TCP port (default {DEFAULT_PORT}; 0: any free port)")
    g.add_argument("--display-rate", type=options.real("--display-rate", ge=DISPLAY_RATE_MIN, le=DISPLAY_RATE_MAX),
                   default=25.0, metavar="HZ",
                   help=f"frames per second sent to the page (default 25, {DISPLAY_RATE_MIN:g} to {DISPLAY_RATE_MAX:g})")
    g.add_argument("--history", type=options.real("--history", gt=0, le=HISTORY_MAX_S), default=HISTORY_MAX_S,
                   metavar="S", help=f"seconds of chart history kept for the page (the longest window; default "
                   f"and most {HISTORY_MAX_S:g})")
    g.add_argument("--stall", type=options.real("--stall", gt=0, le=STALL_MAX_S), default=1.0, metavar="S",
                   help="seconds without a sample before the page says the stream stalled (at least "
                   "four sample intervals; default 1)")
    g.add_argument("--record", metavar="CSV", default=None,
                   help="keep the recording in this file (written as CSV.part, renamed at the end); "
                   "default: a temporary file, removed at the end")
    g = p.add_argument_group("replay and simulator")
    g.add_argument("--speed", type=options.real("--speed", ge=SPEED_RANGE[0], le=SPEED_RANGE[1]), default=1.0,
                   help=f"times real time (default 1, {SPEED_RANGE[0]:g} to {SPEED_RANGE[1]:g})")
    g = p.add_argument_group("serial port")
    g.add_argument("--baud", type=_int_range("--baud", 50, 4_000_000), default=9600,
                   help="line rate (default 9600, 8N1)")
    g.add_argument("--block-size", type=_int_range("--block-size", 6, 60), default=6,
                   help="data bytes per link block, a multiple of 6 (default 6)")
    g.add_argument("--impl", choices=("c", "python"), default="c", help="receiver B: the C machine or the Python one")
    g.add_argument("--gap-timeout-ms", type=_int_range("--gap-timeout-ms", 1, 32767), default=20,
                   help="max gap inside a block (ms, default 20)")
    g.add_argument("--period", type=_positive("--period"), default=None, metavar="S",
                   help="gyro sample period (default: the BOOT report's, 0.02 s until one comes)")
    g.add_argument("--gyro-zero", type=_triple("--gyro-zero"), default=None, metavar="CODE[,C,C]",
                   help="ADC code at zero rate (default 2048, as attitude-rx)")
    g.add_argument("--gyro-scale", type=_triple("--gyro-scale"), default=None, metavar="K[,K,K]",
                   help="rad/s per code (default 90 deg/s per 2048 codes, as attitude-rx)")
    g = p.add_argument_group("estimator (serial port, BROAD recordings)")
    from ..core import METHODS
    from ..view.estimators import AUTO, ESTIMATORS

    g.add_argument("--estimator", choices=[AUTO, *sorted(ESTIMATORS)], default=AUTO,
                   help="attitude estimator (default auto: ahrs when the recording has accelerometer and "
                   "magnetometer data, as BROAD trials do, else the integrator; the page says which runs)")
    g.add_argument("--method", choices=METHODS, default=None,
                   help="integrator method (default rv3; with --estimator auto it asks for the integrator)")
    from ..ahrs_filter import setting_option

    g.add_argument("--ahrs-setting", type=setting_option("--ahrs-setting"), action="append", default=None,
                   metavar="NAME=VALUE",
                   help="a setting of the attitude filter (docs/ahrs.md; as attitude ahrs --set), for --replay of a "
                   "BROAD trial and --simulate (with --simulate --estimator ahrs); may be repeated")
    p.set_defaults(func=run)


def _err(msg: str) -> None:
    print(f"attitude view: {msg}", file=sys.stderr, flush=True)


def _make_source(args: argparse.Namespace) -> Any:
    """The source the options ask for. InvalidArgument/TypeError from option
    values are usage errors; AttitudeError/OSError opening it are source errors."""
    from ..view import sources

    if args.stdin:
        return sources.StdinSource(sys.stdin.buffer, "stdin")
    if args.replay is not None:
        return sources.ReplaySource(args.replay, speed=args.speed, estimator=args.estimator, method=args.method,
                                    settings=dict(args.ahrs_setting or ()))
    if args.serial is not None:
        from ..view.sources import DEFAULT_SCALE, DEFAULT_ZERO_CODE

        return sources.SerialSource(args.serial, baud=args.baud, block_size=args.block_size, impl=args.impl,
                                    gap_timeout_ms=args.gap_timeout_ms, estimator=args.estimator,
                                    method=args.method, period=args.period,
                                    zero=args.gyro_zero if args.gyro_zero is not None else DEFAULT_ZERO_CODE,
                                    scale=args.gyro_scale if args.gyro_scale is not None else DEFAULT_SCALE)
    from ..view.simsource import SimulatorSource, parse_simulate_options

    return SimulatorSource(parse_simulate_options(args.simulate, ahrs_settings=dict(args.ahrs_setting or ())),
                           speed=args.speed)


def _usage_problems(args: argparse.Namespace) -> str | None:
    from ..view.estimators import AUTO, ESTIMATORS

    serial_only = {"baud": 9600, "block_size": 6, "impl": "c", "gap_timeout_ms": 20, "period": None,
                   "gyro_zero": None, "gyro_scale": None}
    if args.serial is None:
        given = [k for k, d in serial_only.items() if getattr(args, k) != d]
        if given:
            return f"--{given[0].replace('_', '-')} is an option of --serial"
    if args.serial is None and args.replay is None and (args.estimator != AUTO or args.method is not None):
        return ("--estimator and --method are for --serial and --replay (with --simulate, give simulate's "
                "--method after --simulate)")
    if args.ahrs_setting and args.replay is None and args.simulate is None:
        return "--ahrs-setting is for --replay and --simulate (the serial link carries no accelerometer)"
    if args.ahrs_setting:
        from ..ahrs_filter import check_settings

        try:
            check_settings(dict(args.ahrs_setting))
        except (ValueError, TypeError) as exc:
            return f"--ahrs-setting: {exc}"
    if args.speed != 1.0 and args.replay is None and args.simulate is None:
        return "--speed is for --replay and --simulate"
    if args.serial is not None:
        from ..link import block

        size = block.fmt().size
        if args.block_size % size:
            return f"--block-size: must be a multiple of {size} (records of the block format), got {args.block_size}"
    if args.serial is not None and args.estimator != AUTO and ESTIMATORS[args.estimator].needs_acc:
        return f"--estimator {args.estimator} needs accelerometer samples, which the serial link does not carry"
    return None


def run(args: argparse.Namespace) -> int:
    from ..view import server

    if not server.available():
        _err("cannot serve: needs aiohttp: pip install 'attitude-c[view]'")
        return EXIT_SERVE
    problem = _usage_problems(args)
    if problem:
        _err(problem)
        return EXIT_USAGE
    try:
        source = _make_source(args)
    except (AttitudeError, OSError, ValueError, TypeError, ImportError) as exc:
        _err(str(exc))  # simulate's configuration is made of options; the others open something
        return EXIT_USAGE if args.simulate is not None else EXIT_SOURCE
    from ..view.stream import Hub, Recorder

    try:
        recorder = Recorder(args.record)
    except OSError as exc:
        _err(f"cannot write the recording {args.record!r}: {exc.strerror or exc}")
        return EXIT_SOURCE
    try:
        sock = server.listen(args.bind, args.port)
    except OSError as exc:
        recorder.close()
        _err(f"cannot listen on {args.bind} port {args.port}: {exc.strerror or exc}")
        return EXIT_SERVE
    port = sock.getsockname()[1]
    hosts = server.HostPolicy.for_bind(args.bind, args.allow_host)
    url = _url(sock)
    if not server.is_loopback(args.bind):
        _err(f"warning: listening on {args.bind}, not the loopback address: anyone who can reach this "
             f"machine on port {port} can watch the attitude and download the recording (the page "
             "cannot change anything)")
    hub = Hub(recorder=recorder, description=source.description, display_rate=args.display_rate,
              history_s=args.history, stall_s=args.stall)

    def ready() -> None:
        print(f"attitude view: {url}  ({source.description}; Ctrl-C to stop)", flush=True)

    async def main() -> None:
        stop = asyncio.Event()
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, stop.set)
        await server.serve(hub, source, sock, stop, hosts=hosts, on_ready=ready)

    try:
        asyncio.run(main())
    except KeyboardInterrupt:  # a second Ctrl-C during the shutdown
        pass
    finally:
        sock.close()
        kept = recorder.close(complete=hub.failure is None)
    samples, events = recorder.counts()
    where = f" in {kept}" if kept is not None else ""
    _err(f"stopped: {samples} samples and {events} events recorded{where}")
    why = recorder.error or (f"a display tick failed ({hub.failure})" if hub.failure else None)
    if why is not None:
        _err(f"the recording is incomplete: {why}")
        return EXIT_SOURCE
    return EXIT_OK


def _url(sock: Any) -> str:
    """The page's URL: the address listened on (this machine's loopback one for a wildcard)."""
    host, port = sock.getsockname()[:2]
    host = {"0.0.0.0": "127.0.0.1", "::": "::1"}.get(host, host)
    return f"http://{host if ':' not in host else f'[{host}]'}:{port}/"
