"""The host display: live attitude in a web browser (``attitude view``).

A source (attitude-rx's JSON Lines on stdin, a serial port through the
Python host end, a recording replayed, the simulator) pushes samples into a
:class:`~attitude_c.view.stream.Hub`, which records every sample (CSV on
disk) and decimates the stream to the display rate for any number of
browser tabs; :mod:`attitude_c.view.server` serves the page and pushes the
frames over a WebSocket. See docs/view.md.

- :mod:`~attitude_c.view.stream`: the sample layout, the hub, the recorder;
- :mod:`~attitude_c.view.sources`: stdin, recordings, serial port;
- :mod:`~attitude_c.view.simsource`: the simulator (a thin adapter over
  :mod:`attitude_c.sim`);
- :mod:`~attitude_c.view.estimators`: the attitude estimators a source of
  raw gyro samples can run (the integrator today; the attitude filter plugs
  in there);
- :mod:`~attitude_c.view.server`: the web server (aiohttp, the ``view`` extra).
"""

from __future__ import annotations

from .stream import COLUMNS, CSV_HEADER, Client, Hub, Recorder, SourceState, row

__all__ = ["COLUMNS", "CSV_HEADER", "Client", "Hub", "Recorder", "SourceState", "row"]
