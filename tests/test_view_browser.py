"""attitude view in a real browser: Debian's chromium, headless, driven by
Playwright (its own browser download is not used). A source holding a known
attitude: the readouts show it within display rounding, the attitude
indicator's horizon is drawn at the roll (its DOM state, and the sky/ground
boundary fitted on the canvas pixels) and offset by the pitch; the states
"no data" and "source lost"; the page reconnecting after the server
restarts; pause, zoom, download and two tabs at 200 samples/s from the
simulator; and the short version of the soak (``invoke view-soak``).
Screenshots are saved as test artifacts (results/test-artifacts/, or
$ATTITUDE_TEST_ARTIFACTS).

Locally these tests skip with what to install; in CI they must run
(scripts/setup.sh installs chromium and playwright)."""

from __future__ import annotations

import csv
import json
import math
import os
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, _missing

import attitude_c

pytestmark = pytest.mark.slow

ARTIFACTS = Path(os.environ.get("ATTITUDE_TEST_ARTIFACTS", ROOT / "results" / "test-artifacts"))


@pytest.fixture(scope="module")
def browser():
    from toolchain.tasks.view import browser_missing, launch_chromium

    why = browser_missing()
    if why is not None:
        _missing(why)
    try:
        import aiohttp  # noqa: F401
    except ImportError:
        _missing("needs aiohttp: pip install -e '.[test]'")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        b = launch_chromium(pw)
        try:
            yield b
        finally:
            b.close()


def _view(*args: str, **kw):
    from toolchain.tasks.view import ViewProcess

    return ViewProcess(*args, **kw)


class Feeder:
    """attitude-rx-shaped JSON Lines at ``rate_hz`` into a view's stdin, holding
    one attitude (Euler angles in degrees; the yaw turning at ``yaw_rate_dps``),
    until stopped."""

    def __init__(self, proc: subprocess.Popen, euler_deg: tuple[float, float, float], rate_hz: float = 100.0,
                 yaw_rate_dps: float = 0.0) -> None:
        self.proc = proc
        self.euler = np.radians(euler_deg)
        self.yaw_rate = math.radians(yaw_rate_dps)
        self.q = attitude_c.euler_to_quat(self.euler).tolist()
        self.rate = rate_hz
        self.stop = threading.Event()
        self.th = threading.Thread(target=self._run, daemon=True)
        self.th.start()

    def _run(self) -> None:
        k = 0
        t0 = time.monotonic()
        while not self.stop.is_set():
            q = self.q
            if self.yaw_rate:
                q = attitude_c.euler_to_quat(self.euler + [self.yaw_rate * k / self.rate, 0.0, 0.0]).tolist()
            line = json.dumps({"t": k / self.rate, "n": k, "q": q}) + "\n"
            try:
                self.proc.stdin.write(line.encode())
                self.proc.stdin.flush()
            except (BrokenPipeError, ValueError, OSError):
                return
            k += 1
            time.sleep(max(0.0, t0 + k / self.rate - time.monotonic()))

    def close(self, close_stdin: bool = True) -> None:
        self.stop.set()
        self.th.join(5)
        if close_stdin:
            try:
                self.proc.stdin.close()
            except OSError:
                pass


def io_text(path: Path) -> list[str]:
    return path.read_text(encoding="utf-8").splitlines()


def _shot(page, name: str) -> Path:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    p = ARTIFACTS / f"{name}.png"
    page.screenshot(path=str(p), full_page=True)
    return p


# The sky/ground boundary of the attitude indicator, from its pixels: in columns
# across the middle of the dial, the first ground-coloured pixel below a
# sky-coloured one (anything else -- the white horizon line, the ladder, the
# symbol -- is skipped); a least-squares line through those points.
FIT_HORIZON_JS = """
(c) => {
  const ctx = c.getContext('2d');
  const W = c.width, H = c.height;
  const img = ctx.getImageData(0, 0, W, H).data;
  const hex = (h) => [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16));
  const sky = hex(c.dataset.sky), ground = hex(c.dataset.ground);
  const near = (i, col) => Math.abs(img[i] - col[0]) + Math.abs(img[i + 1] - col[1]) + Math.abs(img[i + 2] - col[2]) < 30;
  const R = Math.min(W, H) / 2;
  const pts = [];
  for (let x = Math.round(W / 2 - 0.95 * R); x <= W / 2 + 0.95 * R; x += 2) {
    if (Math.abs(x - W / 2) < 0.6 * R) continue;  // the aircraft symbol's wings
    let lastSky = -1;
    for (let y = 0; y < H; y++) {
      const i = 4 * (y * W + x);
      if (near(i, sky)) lastSky = y;
      else if (near(i, ground) && lastSky >= 0) { pts.push([x, (lastSky + y) / 2]); break; }
    }
  }
  const n = pts.length;
  let sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const [x, y] of pts) { sx += x; sy += y; sxx += x * x; sxy += x * y; }
  const slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  const b = (sy - slope * sx) / n;
  // signed distance of the centre below the line (y grows downwards), perpendicular
  const dist = ((W / 2) * slope + b - H / 2) / Math.sqrt(1 + slope * slope);
  const xs = pts.map((p) => p[0]);
  return {n, xSpan: Math.max(...xs) - Math.min(...xs), angleDeg: Math.atan(-slope) * 180 / Math.PI, distPx: dist,
          R, dpr: window.devicePixelRatio};
}
"""


def _wait_text(page, el_id: str, text: str, *, equal: bool = True, timeout: float = 20_000) -> None:
    """Wait until #el_id exists and its text is (or, equal=False, is no longer) ``text``. A
    function, not a string expression: the page's CSP (no eval) applies to Playwright's string
    predicates. An element the page has not drawn yet (a counter before its first sample) is
    waited for: a predicate that throws ends the wait at once."""
    page.wait_for_function("([id, t, eq]) => { const e = document.getElementById(id); "
                           "return e !== null && (e.textContent === t) === eq; }",
                           arg=[el_id, text, equal], timeout=timeout)


def _wait_attr(page, el_id: str, key: str, value: str, timeout: float = 5_000) -> None:
    page.wait_for_function("([id, k, v]) => document.getElementById(id).dataset[k] === v",
                           arg=[el_id, key, value], timeout=timeout)


def _number(text: str) -> float:
    return float(text.replace("°", "").replace("/s", ""))


def test_known_attitude_readouts_and_horizon(browser) -> None:
    """yaw 35.2°, pitch −12.7°, roll 28.4° held by the source: the readouts say
    so within display rounding (0.05°), the horizon is drawn at the roll and
    offset by the pitch, the heading is 360 − yaw."""
    yaw, pitch, roll = 35.2, -12.7, 28.4
    v = _view("--port", "0", "--stdin", "--display-rate", "20", stdin=subprocess.PIPE)
    feeder = Feeder(v.proc, (yaw, pitch, roll))
    page = browser.new_page(viewport={"width": 1280, "height": 1000})
    try:
        page.goto(v.url)
        page.wait_for_selector("body[data-state=live]", timeout=20_000)
        _wait_text(page, "est-roll", "—", equal=False)
        page.wait_for_timeout(300)  # a few more frames drawn
        shown = {k: page.text_content(f"#est-{k}") for k in ("yaw", "pitch", "roll", "heading")}
        truth = {"yaw": yaw, "pitch": pitch, "roll": roll, "heading": 360.0 - yaw}
        for k, text in shown.items():
            assert text.endswith("°"), (k, text)
            # one decimal shown: within half a unit of the last digit (+ the C round trip, ~1e-12 deg)
            assert abs(_number(text) - truth[k]) <= 0.05 + 1e-9, (k, text, truth[k])
        adi = page.query_selector("#adi")
        assert float(adi.get_attribute("data-horizon-deg")) == pytest.approx(roll, abs=1e-9)
        assert float(adi.get_attribute("data-pitch-deg")) == pytest.approx(pitch, abs=1e-9)
        fit = page.evaluate(FIT_HORIZON_JS, adi)
        # boundary points on both sides of the symbol, at least R apart: each within ±0.5 px
        # (antialiasing), so the slope is good to ~1/R rad ≈ 0.4° for a dial of R ≈ 140 px; 0.6° allows
        # for that and the column sampling
        assert fit["n"] >= 12 and fit["xSpan"] >= fit["R"], fit
        assert fit["angleDeg"] == pytest.approx(roll, abs=0.6), fit
        # nose down: the horizon lies above the centre by |pitch| · R/40 px (40° of pitch from centre to rim)
        R = float(fit["R"]) - 4 * fit["dpr"]
        assert fit["distPx"] == pytest.approx(pitch * R / 40, abs=1.5), fit
        hsi = page.query_selector("#hsi")
        assert float(hsi.get_attribute("data-heading-deg")) == pytest.approx(360 - yaw, abs=1e-6)
        assert page.text_content("#state") == "LIVE" and page.is_hidden("#banner")
        rate = page.text_content("#rate")
        assert "samples/s" in rate
        _shot(page, "view-known-attitude")
    finally:
        page.close()
        feeder.close()
        v.kill()


# Per pixel column of the angle chart's plot area, the rows drawn in the yaw trace's
# colour: opaque (alpha >= 128: the trace line itself, not the 35 % envelope band) and
# within 40 of --yaw in each channel. The plot area's margins are drawChart's (L 46, R 8,
# T 6, B 20 CSS px).
YAW_ROWS_JS = """
(c) => {
  const ctx = c.getContext('2d');
  const dpr = window.devicePixelRatio || 1;
  const W = c.width, H = c.height;
  const img = ctx.getImageData(0, 0, W, H).data;
  const hex = getComputedStyle(document.documentElement).getPropertyValue('--yaw').trim();
  const yaw = [1, 3, 5].map((i) => parseInt(hex.slice(i, i + 2), 16));
  const x0 = Math.ceil(47 * dpr), x1 = Math.floor(W - 9 * dpr), y0 = Math.ceil(7 * dpr), y1 = Math.floor(H - 21 * dpr);
  const rows = [];
  for (let x = x0; x < x1; x++) {
    const col = [];
    for (let y = y0; y < y1; y++) {
      const i = 4 * (y * W + x);
      if (img[i + 3] >= 128 && Math.abs(img[i] - yaw[0]) <= 40 && Math.abs(img[i + 1] - yaw[1]) <= 40
          && Math.abs(img[i + 2] - yaw[2]) <= 40) col.push(y);
    }
    rows.push(col);
  }
  return {rows, plotHeight: y1 - y0};
}
"""


def test_angle_chart_breaks_the_line_where_yaw_wraps(browser) -> None:
    """A yaw turning at 120°/s wraps from +180° to −180° every 3 s: on a 5-s window the
    chart shows wraps, each drawn as two line ends at the chart's ±180° edges. No
    stretch of 32 pixel columns covers more than a third of the chart's rows, as a line
    joining +179° to −179° across one frame's step would (about 0.9 of them)."""
    v = _view("--port", "0", "--stdin", stdin=subprocess.PIPE)
    feeder = Feeder(v.proc, (0.0, 10.0, -20.0), yaw_rate_dps=120.0)
    page = browser.new_page(viewport={"width": 1280, "height": 1000})
    try:
        page.goto(v.url)
        page.wait_for_selector("body[data-state=live]", timeout=20_000)
        page.select_option("#window", "5")
        _wait_attr(page, "chart-angles", "window", "5")
        # 7 s of source time: the 5-s window then holds at least one wrap (one every 3 s)
        page.wait_for_function("() => (window.attitudeView.S.last || {}).t >= 7", timeout=60_000)
        page.click("#pause")  # a still picture to read the pixels of
        page.wait_for_selector("body[data-drawn-paused=true]", timeout=10_000)
        chart = page.query_selector("#chart-angles")
        assert int(chart.get_attribute("data-wraps") or 0) >= 1
        got = page.evaluate(YAW_ROWS_JS, chart)
        rows, height = got["rows"], got["plotHeight"]
        assert sum(1 for r in rows if r) > len(rows) / 2  # the trace is drawn across the chart
        # The line climbs the chart's 418° (360° + 2 × 8 % padding) at 600° per ~1200 px: ~0.3 row per
        # column, so 32 columns cover ~10 rows of line, ~20 at a wrap drawn as two ends. A stroke across
        # the chart covers ~0.9 of the rows within one frame's step (~8 columns at 25 frames/s; 32
        # columns allow a hub ticking 4 times late on a loaded machine).
        widest = max(len(set().union(*map(set, rows[i:i + 32]))) for i in range(len(rows) - 32))
        assert widest < height / 3, (widest, height)
        _shot(page, "view-yaw-wraps")
    finally:
        page.close()
        feeder.close()
        v.kill()


def test_no_data_then_source_lost(browser) -> None:
    v = _view("--port", "0", "--stdin", stdin=subprocess.PIPE)
    page = browser.new_page()
    try:
        page.goto(v.url)
        page.wait_for_selector("body[data-state=waiting]", timeout=20_000)
        assert page.text_content("#banner").startswith("NO DATA")
        assert page.text_content("#state") == "NO DATA"
        feeder = Feeder(v.proc, (0.0, 5.0, -5.0), rate_hz=50)
        page.wait_for_selector("body[data-state=live]", timeout=20_000)
        feeder.close(close_stdin=False)
        page.wait_for_selector("body[data-state=stalled]", timeout=20_000)
        assert page.text_content("#banner").startswith("NO DATA — no data for")
        v.proc.stdin.close()
        page.wait_for_selector("body[data-state=lost]", timeout=20_000)
        assert page.text_content("#banner") == "SOURCE LOST — input ended (stdin closed)"
        assert page.text_content("#state") == "SOURCE LOST"
        _shot(page, "view-source-lost")
    finally:
        page.close()
        v.kill()


def test_page_reconnects_after_the_server_restarts(browser) -> None:
    v1 = _view("--port", "0", "--stdin", stdin=subprocess.PIPE)
    port = v1.port
    f1 = Feeder(v1.proc, (10.0, 0.0, 15.0))
    page = browser.new_page()
    v2 = f2 = None
    try:
        page.goto(v1.url)
        _wait_text(page, "est-roll", "15.0°")
        f1.close()
        rc, _ = v1.stop()
        assert rc == 0
        page.wait_for_selector("body[data-conn=disconnected]", timeout=20_000)
        assert page.text_content("#banner").startswith("SERVER LOST")
        v2 = _view("--port", str(port), "--stdin", stdin=subprocess.PIPE)
        f2 = Feeder(v2.proc, (10.0, 0.0, -40.0))
        _wait_text(page, "est-roll", "-40.0°", timeout=30_000)
        assert page.get_attribute("body", "data-conn") == "connected"
        st = page.evaluate("({c: window.attitudeView.stats.connects, h: window.attitudeView.stats.hellos})")
        assert st == {"c": 2, "h": 2}
    finally:
        page.close()
        for f in (f1, f2):
            if f is not None:
                f.close()
        v1.kill()
        if v2 is not None:
            v2.kill()


def test_two_tabs_pause_zoom_download_at_200_samples_per_s(browser, tmp_path: Path) -> None:
    """The simulator at 200 samples/s (rv3-reuse) with two tabs: both stay
    live with the truth beside the estimate; pausing one freezes its display
    while the other moves on; the window zooms by the wheel and the selector;
    the download holds every sample so far; drawing stays cheap."""
    v = _view("--port", "0", "--simulate", "--duration", "30", "--period", "0.005", "--method", "rv3-reuse",
              "--calibration", "1")
    ctx = browser.new_context(viewport={"width": 1400, "height": 1100}, accept_downloads=True)
    a, b = ctx.new_page(), ctx.new_page()
    try:
        for pg in (a, b):
            pg.goto(v.url)
        for pg in (a, b):
            pg.wait_for_selector("body[data-state=live]", timeout=120_000)
            _wait_text(pg, "true-roll", "—", equal=False)
        a.wait_for_timeout(1500)
        rate = a.text_content("#rate")
        assert "samples/s" in rate and abs(float(rate.split()[0]) - 200) < 20, rate  # ±10 %: a loaded machine
        _shot(a, "view-simulator")
        # pause a: its readouts and chart end stay put while b's move
        a.click("#pause")
        assert a.get_attribute("#pause", "aria-pressed") == "true"
        # the frozen snapshot is drawn at the next animation frame (late on a loaded machine)
        a.wait_for_selector("body[data-drawn-paused=true]", timeout=10_000)
        frozen = a.text_content("#est-t"), a.get_attribute("#chart-angles", "data-t-end")
        b_before = b.text_content("#est-t")
        a.wait_for_timeout(700)
        assert (a.text_content("#est-t"), a.get_attribute("#chart-angles", "data-t-end")) == frozen
        assert b.text_content("#est-t") != b_before
        a.keyboard.press("Space")  # resume (the keyboard shortcut)
        _wait_text(a, "est-t", frozen[0], equal=False, timeout=5_000)
        # zoom: the wheel over a chart (out: x1.25), the selector
        assert a.get_attribute("#chart-angles", "data-window") == "30"
        a.hover("#chart-angles")
        a.mouse.wheel(0, 100)
        _wait_attr(a, "chart-angles", "window", "37.5")
        a.select_option("#window", "5")
        _wait_attr(a, "chart-angles", "window", "5")
        # download through the page: every sample recorded so far, in order
        with a.expect_download(timeout=30_000) as dl:
            a.click("#download")
        path = tmp_path / "dl.csv"
        dl.value.save_as(path)
        assert dl.value.suggested_filename.startswith("attitude-view-")
        every = list(csv.DictReader(io_text(path)))
        assert every[0]["event"] == "note"  # "simulated 30 s in ... s: 6000 attitude updates"
        rows = [r for r in every if not r["event"]]
        n = [int(r["n"]) for r in rows]
        assert len(n) > 200 and n == list(range(len(n)))
        assert rows[0]["true_q0"] != ""
        for pg in (a, b):
            st = pg.evaluate("({frames: window.attitudeView.stats.frames, missed: window.attitudeView.S.missedFrames, "
                             "median: window.attitudeView.stats.medianDrawMs()})")
            # a draw takes a few ms here; 25 ms would still leave most of a 40-ms frame (25 frames/s)
            assert st["median"] < 25, st
            assert st["frames"] > 50 and st["missed"] <= st["frames"] * 0.1, st
        hub = a.evaluate("window.attitudeView.S.hub")
        assert hub["clients"] == 2
    finally:
        ctx.close()
        v.kill()


def test_soak_smoke(browser) -> None:
    """The short version of ``invoke view-soak``: 6 s at 200 samples/s, two tabs:
    every sample recorded, numbered without a gap, a clean stop."""
    from toolchain.tasks.view import run_soak

    fig = run_soak(6.0, period=0.005, tabs=2, history=5.0, every=1.0, log=lambda s: None, browser=browser)
    assert fig["recorded_samples"] == fig["expected_samples"] == 1200, fig
    assert fig["numbered_0_to_n_minus_1"] and fig["times_increasing"], fig
    assert fig["exit_status"] == 0 and "stopped: 1200 samples" in fig["stopped_line"], fig
    assert all(t["frames"] > 0 for t in fig["tab_stats"]), fig
    # a sanity bound, not the soak's finding: the server is a Python process with NumPy and the
    # C extension loaded (~100-200 MiB); a leak of one copy per sample would show in the long run
    assert fig["rss_max_mb"] < 1024, fig
    assert math.isfinite(fig["rss_growth_second_half_mb"])


def test_filter_bias_and_flags_from_attitude_rx(browser) -> None:
    """attitude-rx's filter lines (--estimator ahrs) on stdin: the page lists the newest gyro-bias
    estimate (°/s) and the filter's flags by name, with their labels."""
    v = _view("--port", "0", "--stdin", "--display-rate", "20", stdin=subprocess.PIPE)
    page = browser.new_page()
    try:
        page.goto(v.url)
        page.wait_for_selector("body[data-state=waiting]", timeout=20_000)
        for k in range(5):  # the shape of attitude_rx.c's print_filter, flags changing on the last line
            flags = '["rest","acc_rejected"]' if k == 4 else "[]"
            line = (f'{{"t":{0.01 * (k + 1)},"n":{k},"codes":[2048,2048,2048],"q":[1,0,0,0],"yaw_deg":0,'
                    f'"pitch_deg":0,"roll_deg":0,"heading_deg":0,"held":0,"rate_dps":[0,0,0],'
                    f'"bias_dps":[0.01234,-0.5,{0.25 * k}],"flags":{flags},"acc_ms2":[0,0,9.81]}}\n')
            v.proc.stdin.write(line.encode())
        v.proc.stdin.flush()
        _wait_text(page, "counter-filter_flags", "rest acc_rejected")
        assert page.text_content("#counter-bias_x_dps") == "0.0123"  # 4 decimals of °/s
        assert page.text_content("#counter-bias_y_dps") == "-0.5"
        assert page.text_content("#counter-bias_z_dps") == "1"
        labels = page.eval_on_selector_all("#counters .kv-item .k", "els => els.map(e => e.textContent)")
        assert {"gyro bias x (°/s)", "gyro bias y (°/s)", "gyro bias z (°/s)", "filter flags"} <= set(labels)
        _shot(page, "view-filter-bias-flags")
    finally:
        page.close()
        v.kill()


def test_gnss_panel_shows_speed_track_and_fix(browser) -> None:
    """attitude-rx's lines with "gnss" objects (issue 30) on stdin: the GNSS panel, hidden before the
    first fix, shows the newest fix's ground speed, track, fix type, satellites, PDOP and the filter's
    GNSS flag, and the ground-speed chart has points."""
    v = _view("--port", "0", "--stdin", "--display-rate", "20", stdin=subprocess.PIPE)
    page = browser.new_page()
    try:
        page.goto(v.url)
        page.wait_for_selector("body[data-state=waiting]", timeout=20_000)
        assert page.is_hidden("#gnss-panel")
        for k in range(40):  # a fix every tenth line, speed 20.0 + k/10 m/s; the last fix rejected
            line = {"t": 0.02 * (k + 1), "n": k, "q": [1, 0, 0, 0], "held": 0, "bias_dps": [0, 0, 0],
                    "flags": ["gnss_aided"] if k < 39 else ["gnss_aided", "gnss_rejected"]}
            if k % 10 == 9:
                line["gnss"] = {"fix": "3d", "valid": True, "speed": 20.0 + k / 10, "track_deg": 45.25,
                                "vel_enu": [14.9, 14.9, None], "sats": 9, "pdop": 1.85, "age_s": 0.1,
                                "source": "gpsd"}
            v.proc.stdin.write((json.dumps(line) + "\n").encode())
        v.proc.stdin.flush()
        _wait_text(page, "gnss-count", "4")
        _wait_text(page, "gnss-aiding", "aided · fix rejected")
        assert page.is_visible("#gnss-panel")
        assert page.text_content("#gnss-speed") == "23.90 m/s (86.0 km/h)"
        assert page.text_content("#gnss-track") == "45.3°"  # 45.25 to one decimal (toFixed rounds up here)
        assert page.text_content("#gnss-fix") == "3D, valid"
        assert page.text_content("#gnss-sats") == "9"
        assert page.text_content("#gnss-pdop") == "1.9"
        assert page.text_content("#gnss-age") == "0.10 s"  # the last fix came on the last line
        assert page.text_content("#gnss-source") == "gpsd"
        page.wait_for_function("() => Number(document.getElementById('chart-gnss-speed').dataset.points) > 0",
                               timeout=5_000)
        _shot(page, "view-gnss-panel")
    finally:
        page.close()
        v.kill()
