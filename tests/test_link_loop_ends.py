"""How the real-time link loops end when nothing is heard (attitude_c.link.transport and
transport2): ``stop`` set, ``duration`` (the sender's ``timeout``) past, ``eof_after``
seconds of silence -- each named in the report. On ``loop://`` (pyserial's echo port): a
receiver hears nothing, a v2 sender only its own frames."""

from __future__ import annotations

import threading
from typing import Any

import pytest

from attitude_c.link.sim2 import record
from attitude_c.link.transport import open_port, run_receiver
from attitude_c.link.transport2 import listen_auto, run_receiver2, run_sender2

RECEIVERS = {
    "run_receiver": lambda port, **kw: run_receiver(port, impl="python", **kw).ended_by,
    "run_receiver2": lambda port, **kw: run_receiver2(port, impl="python", **kw).ended_by,
    "listen_auto": lambda port, **kw: listen_auto(port, impl="python", **kw).ended_by,
}
# (keyword arguments, the ending they must give); the other limits far away (30 s)
ENDS = [
    ({"stop": "set", "duration": 30.0, "eof_after": 30.0}, "stop"),
    ({"duration": 0.05, "eof_after": 30.0}, "duration"),
    ({"duration": 30.0, "eof_after": 0.05}, "eof"),
]


def _stop(kw: dict[str, Any]) -> dict[str, Any]:
    if kw.get("stop") == "set":
        ev = threading.Event()
        ev.set()
        kw = {**kw, "stop": ev}
    return kw


@pytest.mark.parametrize("name", list(RECEIVERS))
@pytest.mark.parametrize(("kw", "ended_by"), ENDS, ids=[e for _, e in ENDS])
def test_receiver_loop_ends(name: str, kw: dict[str, Any], ended_by: str) -> None:
    port = open_port("loop://")
    try:
        assert RECEIVERS[name](port, **_stop(kw)) == ended_by
    finally:
        port.close()


@pytest.mark.parametrize(("kw", "ended_by"), [({"stop": "set", "timeout": 30.0}, "stop"),
                                              ({"timeout": 0.05}, "timeout")], ids=["stop", "timeout"])
def test_sender2_loop_ends(kw: dict[str, Any], ended_by: str) -> None:
    port = open_port("loop://")
    try:
        rep = run_sender2(port, [record(i) for i in range(3)], impl="python", **_stop(kw))
    finally:
        port.close()
    assert rep.ended_by == ended_by and rep.error == ""
    assert (rep.pushed, rep.acknowledged) == (3, 0)  # nobody answers on loop://
