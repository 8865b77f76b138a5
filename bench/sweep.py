"""attitude sweep on Dask: runs per second against worker count, and the
engine's cost per run.

One fixed sweep of short simulator runs (the default chain, 10 s of the
paper's motion at h = 0.08 s: ~0.1 s of CPU each) is run serially in this
process (no Dask), then on a local cluster of 1 and of 2 worker processes
(cluster started before the clock starts; its start-up is reported apart),
and on 2 workers with 8 runs per Dask task (``chunk = 8``).
The engine's cost per run is the 1-worker wall time per run minus the
serial one (scheduling, serialization, the journal, the client's loop);
the same with runs that do nothing (an empty ``run_chunk``) isolates the
pure scheduling cost. Every sweep writes into a fresh temporary folder, so
nothing is resumed.

    python -m bench.sweep [--quick]     # Markdown on stdout
    invoke bench --only sweep           # docs/bench/sweep.md
"""

from __future__ import annotations

import logging
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

TITLE = "attitude sweep on Dask: runs/s against workers, engine cost per run"


def _spec(n: int) -> dict[str, Any]:
    return {"sweep": {"name": "bench", "seeds": n},
            "fixed": {"duration": 10, "calibration": 1}}


def _timed(spec: Any, client: Any, folder: Path) -> float:
    from attitude_c.sim import sweeps

    t = time.perf_counter()
    df = sweeps.sweep(spec, client, out=folder, plots=False)
    wall = time.perf_counter() - t
    assert df.attrs["executed"] == len(spec.runs) and df.attrs["failed"] == 0
    return wall


def _worker_cpu() -> float:
    import resource

    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _noop_rate(client: Any, n: int) -> tuple[float, float, float]:
    """Per empty task through the client (submit, run, gather): wall seconds, CPU seconds of
    this process (client + the local cluster's scheduler, which runs in it) and CPU seconds
    of the workers. The CPU figures include the engine's background threads (heartbeats, the
    workers' sampling profiler) over the wall time, so they too grow with the load."""
    from distributed import as_completed

    from attitude_c.sim.sweeps import run_chunk

    w0 = sum(client.run(_worker_cpu).values())
    c0 = time.process_time()
    t = time.perf_counter()
    futs = [client.submit(run_chunk, "simulate", [], None, {}, pure=False) for _ in range(n)]
    for f in as_completed(futs):
        f.result()
    wall = (time.perf_counter() - t) / n
    cpu = (time.process_time() - c0) / n
    w1 = sum(client.run(_worker_cpu).values())
    return wall, cpu, (w1 - w0) / n


def run(quick: bool = False) -> str:
    import distributed

    from attitude_c.sim import sweeps

    n = 24 if quick else 80
    spec = sweeps.load_spec(_spec(n))
    chunked = sweeps.load_spec({**_spec(n), "sweep": {**_spec(n)["sweep"], "chunk": 8}})
    load0 = os.getloadavg()
    rows: list[tuple[str, float, float]] = []  # engine, wall s, runs/s
    startup: dict[int, float] = {}
    noop: dict[int, tuple[float, float, float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp)
        sweeps.sweep(sweeps.load_spec(_spec(2)), "serial", out=base / "warm", plots=False)  # imports, caches
        wall = _timed(spec, "serial", base / "serial")
        rows.append(("serial (this process, no Dask)", wall, n / wall))
        for w in (1, 2):
            t = time.perf_counter()
            cluster = distributed.LocalCluster(n_workers=w, threads_per_worker=1, processes=True,
                                               dashboard_address=":0", silence_logs=logging.CRITICAL)
            client = distributed.Client(cluster)
            client.run(lambda: __import__("attitude_c.sim.sweeps"))  # workers import the package
            startup[w] = time.perf_counter() - t
            try:
                wall = _timed(spec, client, base / f"w{w}")
                rows.append((f"local cluster, {w} worker process(es)", wall, n / wall))
                if w == 2:  # 8 runs per Dask task: the engine's cost shared by 8
                    wall = _timed(chunked, client, base / "w2c8")
                    rows.append(("local cluster, 2 workers, `chunk = 8`", wall, n / wall))
                noop[w] = _noop_rate(client, 200 if quick else 1000)
            finally:
                client.close()
                cluster.close()
    load1 = os.getloadavg()
    serial_per_run = rows[0][1] / n
    overhead = rows[1][1] / n - serial_per_run
    lines = [
        (f"Sweep: {n} runs of `attitude simulate --duration 10 --calibration 1` (default chain, one seed "
        f"each), {serial_per_run * 1e3:.0f} ms of work per run serially. Load average of the machine "
        f"(shared) before/after: {load0[0]:.1f} / {load1[0]:.1f} on {os.cpu_count()} CPUs; "
        f"Python {sys.version.split()[0]}, dask {distributed.__version__}."),
        "",
        "| engine | wall (s) | runs/s | speed-up vs serial |",
        "|---|---:|---:|---:|",
    ]
    for name, wall, rate in rows:
        lines.append(f"| {name} | {wall:.2f} | {rate:.1f} | {rate / rows[0][2]:.2f}× |")
    lines += [
        "",
        (f"Engine cost per run (1 worker wall per run − serial wall per run): **{overhead * 1e3:.1f} ms** "
         f"(wall: grows with the machine's load). Local cluster start-up (not in the walls above): "
         f"{startup[1]:.1f} s (1 worker), {startup[2]:.1f} s (2 workers)."),
        "",
        "Empty tasks (an empty `run_chunk`) through the client, per task:",
        "",
        "| workers | wall (ms) | CPU of client + scheduler (ms) | CPU of the workers (ms) |",
        "|---:|---:|---:|---:|",
    ]
    for w in (1, 2):
        lines.append(f"| {w} | {noop[w][0] * 1e3:.2f} | {noop[w][1] * 1e3:.2f} | {noop[w][2] * 1e3:.2f} |")
    lines += ["", ("CPU columns: the engine's processes' CPU time over the test divided by the tasks, "
                   "background threads (heartbeats, the workers' profiler) included, so on a loaded "
                   "machine they grow with the wall time too. distributed documents about 1 ms of "
                   "overhead per task on an idle machine; on a shared, loaded one every hop between "
                   "client, scheduler and worker waits for a CPU.")]
    return "\n".join(lines)


if __name__ == "__main__":
    print(run(quick="--quick" in sys.argv))
