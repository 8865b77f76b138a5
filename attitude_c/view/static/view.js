// attitude view: the page. One WebSocket from the server (frames at the display
// rate), canvases drawn when something changed. No external library.
// For tests, the state is exposed on the DOM: body[data-conn|data-state], the
// readouts' text, #adi[data-roll-deg|data-pitch-deg|data-horizon-deg] (the
// angle, counter-clockwise on screen, at which the horizon was drawn), and
// window.attitudeView (frame and draw statistics).
"use strict";

(function () {
  const $ = (id) => document.getElementById(id);
  const DEG = Math.PI / 180;
  const COLORS = {};
  const css = getComputedStyle(document.documentElement);
  for (const k of ["yaw", "pitch", "roll", "truth", "text", "dim", "line", "bad", "warn", "ok"]) {
    COLORS[k] = css.getPropertyValue("--" + k).trim() || "#ccc";
  }
  const SKY = "#2f6db5";
  const GROUND = "#8a5a2b";

  const S = {
    conn: "connecting", state: "waiting", text: "", source: "", session: null,
    col: {}, points: [], last: null, gnss: null, counters: {}, hub: {}, events: [],
    historyS: 600, displayRate: 25, seq: 0, missedFrames: 0,
    paused: false, frozen: null, windowS: 30, rate: {},
    dirty: true, retryMs: 500, ws: null,
  };
  const drawTimes = []; // the last 200 draw times (ms)
  const stats = {
    frames: 0, hellos: 0, draws: 0, lastDrawMs: 0, maxDrawMs: 0, connects: 0,
    medianDrawMs: () => {
      if (!drawTimes.length) return null;
      const s = drawTimes.slice().sort((a, b) => a - b);
      return s[s.length >> 1];
    },
  };
  window.attitudeView = { S: S, stats: stats };

  // ---- connection -------------------------------------------------------------
  function connect() {
    const proto = location.protocol === "https:" ? "wss:" : "ws:";
    let ws;
    try {
      ws = new WebSocket(proto + "//" + location.host + "/ws");
    } catch (e) {
      scheduleReconnect();
      return;
    }
    S.ws = ws;
    ws.onopen = () => { S.retryMs = 500; stats.connects += 1; setConn("connected"); };
    ws.onmessage = (ev) => {
      let m;
      try { m = JSON.parse(ev.data); } catch (e) { return; }
      if (m.type === "hello") onHello(m);
      else if (m.type === "history") onHistory(m);
      else if (m.type === "frame") onFrame(m);
    };
    ws.onclose = () => {
      if (S.ws === ws) { S.ws = null; setConn("disconnected"); scheduleReconnect(); }
    };
    ws.onerror = () => { try { ws.close(); } catch (e) { /* closing anyway */ } };
  }

  function scheduleReconnect() {
    const ms = S.retryMs;
    S.retryMs = Math.min(2000, S.retryMs * 2);
    setTimeout(connect, ms);
  }

  function setConn(c) {
    S.conn = c;
    document.body.dataset.conn = c;
    S.dirty = true;
    updateStatus();
  }

  function onHello(m) {
    stats.hellos += 1;
    // a snapshot of the same session (a reconnect, or the server resyncing a tab that fell
    // behind) keeps what a paused display froze; a new session freezes afresh
    const keepFrozen = S.paused && S.frozen && S.session === m.session;
    S.session = m.session;
    S.source = m.source || "";
    S.historyS = m.history_s || 600;
    S.displayRate = m.display_rate || 25;
    S.col = {};
    (m.columns || []).forEach((name, i) => { S.col[name] = i; });
    S.points = (m.history || []).slice();
    S.last = m.last || null;
    S.gnss = m.gnss || null;
    S.events = (m.events || []).slice(-200);
    S.counters = m.counters || {};
    S.hub = m.hub || {};
    S.seq = m.seq || 0;
    S.state = m.state; S.text = m.text || "";
    if (!keepFrozen) {
      S.frozen = null;
      if (S.paused) freeze();
    }
    $("source").textContent = S.source;
    $("source").title = S.source;
    $("session").textContent = "session " + S.session;
    for (const opt of $("window").options) opt.disabled = Number(opt.value) > S.historyS;
    if (S.windowS > S.historyS) setWindow(S.historyS);
    renderEvents(null);
    renderCounters();
    updateStatus();
    S.dirty = true;
  }

  // the history follows the hello in messages of a few hundred points, oldest first,
  // before any frame (the server sends them one at a time)
  function onHistory(m) {
    for (const p of m.points || []) S.points.push(p);
    trim();
    S.dirty = true;
  }

  function onFrame(m) {
    stats.frames += 1;
    if (m.seq !== S.seq + 1) S.missedFrames += Math.max(0, m.seq - S.seq - 1);
    S.seq = m.seq;
    S.state = m.state; S.text = m.text || "";
    S.rate = m.rate || {};
    if (m.counters) S.counters = m.counters;
    if (m.hub) S.hub = m.hub;
    if (m.gnss) S.gnss = m.gnss;
    if (m.point) {
      S.points.push(m.point);
      S.last = m.last;
      trim();
    }
    if (m.events) {
      for (const e of m.events) S.events.push(e);
      if (S.events.length > 200) S.events.splice(0, S.events.length - 200);
      renderEvents(m.events);
    }
    renderCounters();
    updateStatus();
    S.dirty = true;
  }

  function trim() {
    const pts = S.points;
    if (!pts.length) return;
    const tEnd = pts[pts.length - 1][0];
    let k = 0;
    while (k < pts.length && pts[k][0] < tEnd - S.historyS) k++;
    if (k > 0) pts.splice(0, k);
  }

  // ---- status, counters, events -------------------------------------------------
  const STATE_WORDS = { live: "LIVE", waiting: "NO DATA", stalled: "NO DATA", lost: "SOURCE LOST",
                        ended: "SOURCE ENDED", disconnected: "SERVER LOST", connecting: "CONNECTING" };

  function viewState() {
    if (S.conn !== "connected") return S.conn === "connecting" ? "waiting" : "disconnected";
    return S.state || "waiting";
  }

  function updateStatus() {
    const vs = viewState();
    document.body.dataset.state = vs;
    const badge = $("state");
    badge.dataset.state = vs;
    badge.dataset.paused = S.paused ? "true" : "false";
    badge.textContent = STATE_WORDS[vs] || vs.toUpperCase();
    const banner = $("banner");
    let msg = "";
    if (vs === "disconnected") msg = "SERVER LOST — the display server stopped; reconnecting…";
    else if (S.conn === "connecting") msg = "NO DATA — connecting to the server…";
    else if (vs === "waiting") msg = "NO DATA — " + (S.text || "waiting for the source");
    else if (vs === "stalled") msg = "NO DATA — " + S.text;
    else if (vs === "lost") msg = "SOURCE LOST — " + S.text;
    else if (vs === "ended") msg = "SOURCE ENDED — " + S.text;
    banner.hidden = !msg;
    banner.dataset.kind = vs;
    banner.textContent = msg;
    const r = S.rate || {};
    const parts = [];
    if (r.samples != null && isFinite(r.samples)) parts.push(r.samples.toFixed(1) + " samples/s");
    if (r.records != null && isFinite(r.records)) parts.push(r.records.toFixed(1) + " updates/s");
    $("rate").textContent = parts.length ? parts.join(" · ") : "—";
  }

  const KNOWN = [
    ["blocks", "blocks accepted"], ["naks", "NAKs"], ["timeouts", "timeouts"], ["duplicates", "duplicates"],
    ["gave_up", "gave up"], ["GAVE_UP", "GAVE_UP reports"], ["BOOT", "BOOT reports"],
    ["OVERRUN", "OVERRUN reports"], ["SELFTEST", "SELFTEST reports"], ["ADC_ERROR", "ADC_ERROR reports"],
    ["error", "bad records"], ["held", "samples held"], ["missing", "samples missing"],
  ];
  // labels of counters a source may add (shown when present): attitude-rx's filter fields
  const LABELS = { bias_x_dps: "gyro bias x (°/s)", bias_y_dps: "gyro bias y (°/s)",
                   bias_z_dps: "gyro bias z (°/s)", filter_flags: "filter flags" };
  const HUB = [["samples", "samples received"], ["recorded", "samples recorded"],
               ["frames_dropped", "display frames dropped"], ["clients", "tabs connected"]];

  function renderCounters() {
    const box = $("counters");
    const rows = [];
    const seen = new Set();
    for (const [k, label] of KNOWN) { rows.push([k, label, S.counters[k]]); seen.add(k); }
    for (const k of Object.keys(S.counters).sort()) {
      if (!seen.has(k)) rows.push([k, LABELS[k] || k.replace(/_/g, " "), S.counters[k]]);
    }
    for (const [k, label] of HUB) rows.push(["hub-" + k, label, S.hub[k]]);
    rows.push(["hub-missed", "frames missed by this tab", S.missedFrames]);
    if (S.hub.recording_error) rows.push(["hub-recording-error", "recording error", S.hub.recording_error]);
    const keys = rows.map((r) => r[0]).join("|");
    if (box.dataset.keys !== keys) {
      box.textContent = "";
      for (const [key, label] of rows) {
        const item = document.createElement("div");
        item.className = "kv-item";
        const k = document.createElement("span");
        k.className = "k";
        k.textContent = label;
        const v = document.createElement("span");
        v.className = "v";
        v.id = "counter-" + key;
        item.append(k, v);
        box.appendChild(item);
      }
      box.dataset.keys = keys;
    }
    for (const [key, , value] of rows) {
      const v = $("counter-" + key);
      const absent = value === undefined || value === null;
      const text = absent ? "—" : String(value);
      if (v.textContent !== text) v.textContent = text;
      v.classList.toggle("absent", absent);
    }
  }

  function describeEvent(e) {
    const d = e.detail || {};
    if (e.kind === "note" && typeof d.note === "string") {
      return (e.t == null ? "" : "t=" + Number(e.t).toFixed(3) + " s ") + d.note;
    }
    const parts = Object.keys(d).map((k) => k + "=" + (typeof d[k] === "object" ? JSON.stringify(d[k]) : d[k]));
    const t = e.t == null ? "" : "t=" + Number(e.t).toFixed(3) + " s ";
    return t + e.kind + (parts.length ? " " + parts.join(" ") : "");
  }

  function renderEvents(fresh) {
    // fresh: the events just received (prepended); none: everything again (a hello)
    const ol = $("events");
    if (!fresh) {
      ol.textContent = "";
      for (const e of S.events.slice(-100)) prepend(ol, e);
    } else {
      for (const e of fresh) prepend(ol, e);
    }
    while (ol.childElementCount > 100) ol.removeChild(ol.lastChild);
  }

  function prepend(ol, e) {
    const li = document.createElement("li");
    li.textContent = describeEvent(e);
    li.className = e.kind === "error" ? "error" : (e.kind === "note" ? "" : "report");
    ol.insertBefore(li, ol.firstChild);
  }

  // ---- controls ---------------------------------------------------------------------
  function freeze() {
    const pts = S.points;
    S.frozen = { last: S.last, gnss: S.gnss, tEnd: pts.length ? pts[pts.length - 1][0] : 0 };
  }

  function setPaused(p) {
    S.paused = p;
    if (p) freeze(); else S.frozen = null;
    const b = $("pause");
    b.textContent = p ? "Resume" : "Pause";
    b.setAttribute("aria-pressed", p ? "true" : "false");
    updateStatus();
    S.dirty = true;
  }

  function fmtWindow(s) {
    if (s >= 60) return (s / 60).toFixed(s % 60 ? 1 : 0) + " min";
    return (s >= 10 ? s.toFixed(0) : s.toFixed(1)) + " s";
  }

  function setWindow(s) {
    S.windowS = Math.max(1, Math.min(S.historyS, s));
    $("window-now").textContent = fmtWindow(S.windowS);
    const sel = $("window");
    let match = false;
    for (const opt of sel.options) if (Math.abs(Number(opt.value) - S.windowS) < 1e-6) { sel.value = opt.value; match = true; }
    if (!match) sel.selectedIndex = -1;
    S.dirty = true;
  }

  $("pause").addEventListener("click", () => setPaused(!S.paused));
  $("window").addEventListener("change", (e) => setWindow(Number(e.target.value)));
  document.addEventListener("keydown", (e) => {
    if (e.code === "Space" && e.target === document.body) { e.preventDefault(); setPaused(!S.paused); }
  });
  for (const id of ["chart-angles", "chart-rates", "chart-gnss-speed"]) {
    $(id).addEventListener("wheel", (e) => {
      e.preventDefault();
      setWindow(S.windowS * (e.deltaY > 0 ? 1.25 : 0.8));
    }, { passive: false });
  }

  // ---- canvases ---------------------------------------------------------------------
  function prepare(canvas) {
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(10, Math.round(canvas.clientWidth));
    const h = Math.max(10, Math.round(canvas.clientHeight));
    if (canvas.width !== Math.round(w * dpr) || canvas.height !== Math.round(h * dpr)) {
      canvas.width = Math.round(w * dpr);
      canvas.height = Math.round(h * dpr);
    }
    const ctx = canvas.getContext("2d");
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, w, h);
    return { ctx, w, h };
  }

  function failFlag(ctx, w, h, word) {
    // the avionics way: a red cross and a flag over an instrument without valid data
    ctx.save();
    ctx.strokeStyle = COLORS.bad;
    ctx.lineWidth = 3;
    ctx.beginPath();
    ctx.moveTo(w * 0.15, h * 0.15); ctx.lineTo(w * 0.85, h * 0.85);
    ctx.moveTo(w * 0.85, h * 0.15); ctx.lineTo(w * 0.15, h * 0.85);
    ctx.stroke();
    ctx.font = "bold 14px system-ui, sans-serif";
    const tw = ctx.measureText(word).width;
    ctx.fillStyle = COLORS.bad;
    ctx.fillRect(w / 2 - tw / 2 - 8, h / 2 - 12, tw + 16, 24);
    ctx.fillStyle = "#fff";
    ctx.textAlign = "center";
    ctx.textBaseline = "middle";
    ctx.fillText(word, w / 2, h / 2);
    ctx.restore();
  }

  function drawADI(last, flag) {
    const canvas = $("adi");
    const { ctx, w, h } = prepare(canvas);
    const cx = w / 2, cy = h / 2, R = Math.min(w, h) / 2 - 4;
    const roll = last && last.roll != null ? last.roll : 0;
    const pitch = last && last.pitch != null ? last.pitch : 0;
    const ppd = R / 40; // pixels per degree of pitch: +-40 deg visible
    ctx.save();
    ctx.beginPath();
    ctx.arc(cx, cy, R, 0, 2 * Math.PI);
    ctx.clip();
    ctx.translate(cx, cy);
    ctx.rotate(-roll * DEG); // right wing down (roll > 0): the horizon turns counter-clockwise
    ctx.translate(0, pitch * ppd); // nose up: the horizon goes down
    ctx.fillStyle = SKY;
    ctx.fillRect(-3 * R, -6 * R, 6 * R, 6 * R);
    ctx.fillStyle = GROUND;
    ctx.fillRect(-3 * R, 0, 6 * R, 6 * R);
    ctx.strokeStyle = "#fff";
    ctx.lineWidth = 2;
    ctx.beginPath(); ctx.moveTo(-3 * R, 0); ctx.lineTo(3 * R, 0); ctx.stroke();
    ctx.lineWidth = 1.2;
    ctx.fillStyle = "#fff";
    ctx.font = "11px system-ui, sans-serif";
    ctx.textBaseline = "middle";
    for (let p = -90; p <= 90; p += 5) {
      if (p === 0) continue;
      const y = -p * ppd;
      const half = p % 10 === 0 ? R * 0.22 : R * 0.1;
      ctx.beginPath(); ctx.moveTo(-half, y); ctx.lineTo(half, y); ctx.stroke();
      if (p % 10 === 0) {
        ctx.textAlign = "left"; ctx.fillText(String(Math.abs(p)), half + 4, y);
        ctx.textAlign = "right"; ctx.fillText(String(Math.abs(p)), -half - 4, y);
      }
    }
    ctx.restore();
    // truth: a dashed horizon
    if (last && last.true && last.true.roll != null) {
      ctx.save();
      ctx.beginPath(); ctx.arc(cx, cy, R, 0, 2 * Math.PI); ctx.clip();
      ctx.translate(cx, cy);
      ctx.rotate(-last.true.roll * DEG);
      ctx.translate(0, last.true.pitch * ppd);
      ctx.setLineDash([8, 6]);
      ctx.strokeStyle = COLORS.truth;
      ctx.lineWidth = 2;
      ctx.beginPath(); ctx.moveTo(-R, 0); ctx.lineTo(R, 0); ctx.stroke();
      ctx.restore();
    }
    // roll scale and pointer
    ctx.save();
    ctx.translate(cx, cy);
    ctx.strokeStyle = "#fff";
    ctx.lineWidth = 1.5;
    for (const a of [-60, -45, -30, -20, -10, 0, 10, 20, 30, 45, 60]) {
      const t = (a - 90) * DEG;
      const r0 = R * (a % 30 === 0 ? 0.84 : 0.89);
      ctx.beginPath();
      ctx.moveTo(r0 * Math.cos(t), r0 * Math.sin(t));
      ctx.lineTo(R * 0.95 * Math.cos(t), R * 0.95 * Math.sin(t));
      ctx.stroke();
    }
    ctx.rotate(-roll * DEG);
    ctx.fillStyle = "#ffd21f";
    ctx.beginPath();
    ctx.moveTo(0, -R * 0.83); ctx.lineTo(-7, -R * 0.83 + 12); ctx.lineTo(7, -R * 0.83 + 12);
    ctx.closePath(); ctx.fill();
    ctx.restore();
    // the aircraft (fixed)
    ctx.save();
    ctx.translate(cx, cy);
    ctx.strokeStyle = "#111"; ctx.lineWidth = 6; ctx.lineCap = "round";
    const wing = () => { ctx.beginPath(); ctx.moveTo(-R * 0.55, 0); ctx.lineTo(-R * 0.2, 0); ctx.lineTo(-R * 0.1, R * 0.08);
      ctx.moveTo(R * 0.55, 0); ctx.lineTo(R * 0.2, 0); ctx.lineTo(R * 0.1, R * 0.08); ctx.stroke(); };
    wing();
    ctx.strokeStyle = "#ffd21f"; ctx.lineWidth = 3.5; wing();
    ctx.fillStyle = "#ffd21f"; ctx.beginPath(); ctx.arc(0, 0, 3.5, 0, 2 * Math.PI); ctx.fill();
    ctx.restore();
    ctx.strokeStyle = COLORS.line; ctx.lineWidth = 2;
    ctx.beginPath(); ctx.arc(cx, cy, R, 0, 2 * Math.PI); ctx.stroke();
    if (flag) failFlag(ctx, w, h, flag);
    canvas.dataset.rollDeg = last ? String(roll) : "";
    canvas.dataset.pitchDeg = last ? String(pitch) : "";
    canvas.dataset.horizonDeg = last ? String(roll) : "";
    canvas.dataset.horizonOffsetPx = last ? String(pitch * ppd) : "";
    canvas.dataset.sky = SKY;
    canvas.dataset.ground = GROUND;
  }

  function drawHSI(last, flag) {
    const canvas = $("hsi");
    const { ctx, w, h } = prepare(canvas);
    const cx = w / 2, cy = h / 2 + 6, R = Math.min(w, h) / 2 - 16;
    const hd = last && last.heading != null ? last.heading : 0;
    ctx.save();
    ctx.translate(cx, cy);
    ctx.fillStyle = "#0d1117";
    ctx.beginPath(); ctx.arc(0, 0, R, 0, 2 * Math.PI); ctx.fill();
    ctx.rotate(-hd * DEG); // the card turns so that the heading is at the top
    ctx.strokeStyle = "#fff"; ctx.fillStyle = "#fff";
    ctx.textAlign = "center"; ctx.textBaseline = "middle";
    for (let a = 0; a < 360; a += 5) {
      const t = (a - 90) * DEG;
      const r0 = R * (a % 30 === 0 ? 0.82 : a % 10 === 0 ? 0.87 : 0.91);
      ctx.lineWidth = a % 10 === 0 ? 1.5 : 1;
      ctx.beginPath(); ctx.moveTo(r0 * Math.cos(t), r0 * Math.sin(t));
      ctx.lineTo(R * 0.97 * Math.cos(t), R * 0.97 * Math.sin(t)); ctx.stroke();
      if (a % 30 === 0) {
        const label = { 0: "N", 90: "E", 180: "S", 270: "W" }[a] || String(a / 10);
        ctx.save();
        ctx.translate(R * 0.7 * Math.cos(t), R * 0.7 * Math.sin(t));
        ctx.rotate(a * DEG);
        ctx.font = (a % 90 === 0 ? "bold 15px" : "12px") + " system-ui, sans-serif";
        ctx.fillStyle = a === 0 ? COLORS.bad : "#fff";
        ctx.fillText(label, 0, 0);
        ctx.restore();
      }
    }
    if (last && last.true && last.true.heading != null) { // truth: a bug on the card
      const t = (last.true.heading - 90) * DEG;
      ctx.fillStyle = COLORS.truth;
      ctx.save(); ctx.rotate(t + Math.PI / 2);
      ctx.beginPath(); ctx.moveTo(0, -R * 0.98); ctx.lineTo(-7, -R * 0.98 + 13); ctx.lineTo(7, -R * 0.98 + 13);
      ctx.closePath(); ctx.fill(); ctx.restore();
    }
    ctx.restore();
    // lubber line, aircraft, readout
    ctx.save();
    ctx.translate(cx, cy);
    ctx.fillStyle = "#ffd21f";
    ctx.beginPath(); ctx.moveTo(0, -R + 2); ctx.lineTo(-7, -R - 10); ctx.lineTo(7, -R - 10); ctx.closePath(); ctx.fill();
    ctx.strokeStyle = "#ffd21f"; ctx.lineWidth = 3; ctx.lineCap = "round";
    ctx.beginPath(); ctx.moveTo(0, -R * 0.3); ctx.lineTo(0, R * 0.3);
    ctx.moveTo(-R * 0.25, -R * 0.02); ctx.lineTo(R * 0.25, -R * 0.02);
    ctx.moveTo(-R * 0.1, R * 0.26); ctx.lineTo(R * 0.1, R * 0.26); ctx.stroke();
    ctx.restore();
    ctx.fillStyle = "#000"; ctx.fillRect(cx - 30, 2, 60, 18);
    ctx.fillStyle = "#fff"; ctx.font = "bold 13px system-ui, sans-serif"; ctx.textAlign = "center"; ctx.textBaseline = "middle";
    ctx.fillText(last ? hd.toFixed(0).padStart(3, "0") + "°" : "---", cx, 11);
    if (flag) failFlag(ctx, w, h, flag);
    canvas.dataset.headingDeg = last ? String(hd) : "";
  }

  // quaternion (scalar first, body -> ENU) applied to a body vector
  function rotate(q, v) {
    const [w, x, y, z] = q;
    const tx = 2 * (y * v[2] - z * v[1]), ty = 2 * (z * v[0] - x * v[2]), tz = 2 * (x * v[1] - y * v[0]);
    return [v[0] + w * tx + (y * tz - z * ty), v[1] + w * ty + (z * tx - x * tz), v[2] + w * tz + (x * ty - y * tx)];
  }

  function drawAxes3D(last, flag) {
    const canvas = $("axes3d");
    const { ctx, w, h } = prepare(canvas);
    const cx = w / 2, cy = h / 2 + h * 0.04, s = Math.min(w, h) * 0.42;
    const az = -35 * DEG, el = 25 * DEG; // camera south-south-west of the origin, looking down a little
    const proj = (v) => {
      const x1 = v[0] * Math.cos(az) - v[1] * Math.sin(az);
      const y1 = v[0] * Math.sin(az) + v[1] * Math.cos(az);
      const z2 = y1 * Math.sin(el) + v[2] * Math.cos(el);
      return [cx + s * x1, cy - s * z2, y1 * Math.cos(el) - v[2] * Math.sin(el)];
    };
    // ground grid and ENU axes
    ctx.strokeStyle = COLORS.line; ctx.lineWidth = 1;
    for (let i = -2; i <= 2; i++) {
      const a = proj([i / 2, -1, 0]), b = proj([i / 2, 1, 0]), c = proj([-1, i / 2, 0]), d = proj([1, i / 2, 0]);
      ctx.beginPath(); ctx.moveTo(a[0], a[1]); ctx.lineTo(b[0], b[1]); ctx.moveTo(c[0], c[1]); ctx.lineTo(d[0], d[1]); ctx.stroke();
    }
    ctx.fillStyle = COLORS.dim; ctx.font = "11px system-ui, sans-serif"; ctx.textAlign = "center"; ctx.textBaseline = "middle";
    for (const [v, l] of [[[1.15, 0, 0], "E"], [[0, 1.15, 0], "N"], [[0, 0, 1.15], "U"]]) {
      const p = proj(v); ctx.fillText(l, p[0], p[1]);
    }
    const o = proj([0, 0, 0]);
    const body = (q, dashed) => {
      const axes = [[[1, 0, 0], COLORS.yaw, "x"], [[0, 1, 0], COLORS.pitch, "y"], [[0, 0, 1], COLORS.roll, "z"]];
      if (!dashed) { // a flat silhouette in the body's x-y plane: nose along y
        const pts = [[0, 0.8, 0], [0.55, -0.35, 0], [0, -0.15, 0], [-0.55, -0.35, 0]].map((v) => proj(rotate(q, v)));
        ctx.fillStyle = "rgba(223, 230, 238, 0.16)";
        ctx.beginPath(); ctx.moveTo(pts[0][0], pts[0][1]);
        for (const p of pts.slice(1)) ctx.lineTo(p[0], p[1]);
        ctx.closePath(); ctx.fill();
      }
      const drawn = axes.map(([v, color, label]) => [proj(rotate(q, v)), color, label]);
      drawn.sort((a, b) => b[0][2] - a[0][2]); // far first
      ctx.setLineDash(dashed ? [6, 5] : []);
      for (const [p, color, label] of drawn) {
        ctx.strokeStyle = dashed ? COLORS.truth : color;
        ctx.lineWidth = dashed ? 1.5 : 3;
        ctx.beginPath(); ctx.moveTo(o[0], o[1]); ctx.lineTo(p[0], p[1]); ctx.stroke();
        if (!dashed) { ctx.fillStyle = color; ctx.font = "bold 12px system-ui, sans-serif"; ctx.fillText(label, p[0] + (p[0] - o[0]) * 0.08, p[1] + (p[1] - o[1]) * 0.08); }
      }
      ctx.setLineDash([]);
    };
    if (last && last.true && last.true.q && last.true.q[0] != null) body(last.true.q, true);
    if (last && last.q && last.q[0] != null) body(last.q, false);
    if (flag) failFlag(ctx, w, h, flag);
  }

  function niceStep(range, target) {
    const raw = range / target;
    const mag = Math.pow(10, Math.floor(Math.log10(raw)));
    for (const m of [1, 2, 2.5, 5, 10]) if (raw <= m * mag) return m * mag;
    return 10 * mag;
  }

  // The pen through a trace's per-column values. A trace with wrap: W (angles in
  // (-W, W]) is broken where two neighbours jump across ±W (|Δ| > W): the line runs
  // to the edge it leaves by and starts again from the opposite edge, instead of a
  // vertical stroke across the chart. Returns the number of wraps drawn so.
  function tracePath(ctx, X, Y, bval, bt, brk, wrap) {
    let pen = false, px0 = 0, v0 = 0, wraps = 0;
    for (let x = 0; x < bval.length; x++) {
      if (isNaN(bval[x])) continue;
      const v = bval[x], px = X(bt[x]);
      if (!pen || brk[x]) ctx.moveTo(px, Y(v));
      else if (wrap && Math.abs(v - v0) > wrap) {
        const edge = v0 > 0 ? wrap : -wrap; // left by this edge, back in by the other
        const f = (edge - v0) / (v + 2 * edge - v0); // where the unwrapped segment crosses it
        const xc = px0 + f * (px - px0);
        ctx.lineTo(xc, Y(edge)); ctx.moveTo(xc, Y(-edge)); ctx.lineTo(px, Y(v));
        wraps++;
      } else ctx.lineTo(px, Y(v));
      pen = true; px0 = px; v0 = v;
    }
    return wraps;
  }

  // Strip chart. traces: [{c: column of the value, lo, hi: envelope columns, color, dash,
  // wrap: W for an angle in (-W, W]}]. Returns the points shown and the wraps broken.
  function drawChart(canvas, traces, tEnd, span) {
    const { ctx, w, h } = prepare(canvas);
    const L = 46, Rm = 8, T = 6, B = 20;
    const pw = w - L - Rm, ph = h - T - B;
    const t0 = tEnd - span;
    const pts = S.points;
    // visible points (binary search for the first)
    let lo = 0, hi = pts.length;
    while (lo < hi) { const mid = (lo + hi) >> 1; if (pts[mid][0] < t0) lo = mid + 1; else hi = mid; }
    const first = Math.max(0, lo - 1);
    let last = first;
    while (last < pts.length && pts[last][0] <= tEnd) last++;
    let ymin = Infinity, ymax = -Infinity;
    for (let i = first; i < last; i++) {
      const p = pts[i];
      for (const tr of traces) {
        const a = p[tr.lo != null ? tr.lo : tr.c], b = p[tr.hi != null ? tr.hi : tr.c];
        if (a != null && a < ymin) ymin = a;
        if (b != null && b > ymax) ymax = b;
      }
    }
    if (!isFinite(ymin)) { ymin = -1; ymax = 1; }
    if (ymax - ymin < 1) { const m = (ymax + ymin) / 2; ymin = m - 0.5; ymax = m + 0.5; }
    const pad = (ymax - ymin) * 0.08;
    ymin -= pad; ymax += pad;
    const X = (t) => L + (t - t0) / span * pw;
    const Y = (v) => T + (ymax - v) / (ymax - ymin) * ph;
    // grid
    ctx.strokeStyle = COLORS.line; ctx.lineWidth = 1; ctx.fillStyle = COLORS.dim;
    ctx.font = "11px system-ui, sans-serif"; ctx.textAlign = "right"; ctx.textBaseline = "middle";
    const ys = niceStep(ymax - ymin, 5);
    for (let v = Math.ceil(ymin / ys) * ys; v <= ymax; v += ys) {
      ctx.beginPath(); ctx.moveTo(L, Y(v)); ctx.lineTo(L + pw, Y(v)); ctx.stroke();
      ctx.fillText(Math.abs(v) < 1e-9 ? "0" : String(+v.toFixed(3)), L - 4, Y(v));
    }
    const xs = niceStep(span, 6);
    ctx.textAlign = "center"; ctx.textBaseline = "top";
    for (let t = Math.ceil(t0 / xs) * xs; t <= tEnd; t += xs) {
      ctx.beginPath(); ctx.moveTo(X(t), T); ctx.lineTo(X(t), T + ph); ctx.stroke();
      ctx.fillText(String(+t.toFixed(2)) + " s", X(t), T + ph + 4);
    }
    ctx.save();
    ctx.beginPath(); ctx.rect(L, T, pw, ph); ctx.clip();
    const gap = Math.max(1.0, 10 / S.displayRate);
    const cols = Math.max(1, Math.floor(pw));
    let wraps = 0;
    for (const tr of traces) {
      // per pixel column: min, max and the newest value (decimation that keeps the peaks)
      const bmin = new Float64Array(cols).fill(NaN), bmax = new Float64Array(cols).fill(NaN);
      const bval = new Float64Array(cols).fill(NaN), bt = new Float64Array(cols).fill(NaN);
      const brk = new Uint8Array(cols);
      let prevT = null, hole = false;
      for (let i = first; i < last; i++) {
        const p = pts[i];
        const v = p[tr.c];
        if (v == null) { prevT = null; hole = true; continue; } // no value (no valid GNSS fix): the line breaks
        const x = Math.min(cols - 1, Math.max(0, Math.floor((p[0] - t0) / span * pw)));
        const a = tr.lo != null && p[tr.lo] != null ? p[tr.lo] : v, b = tr.hi != null && p[tr.hi] != null ? p[tr.hi] : v;
        if (tr.wrap && Math.abs(v - bval[x]) > tr.wrap) { bmin[x] = NaN; bmax[x] = NaN; } // wrapped in this column: its envelope restarts
        if (!(bmin[x] <= a)) bmin[x] = a;
        if (!(bmax[x] >= b)) bmax[x] = b;
        bval[x] = v; bt[x] = p[0];
        if (hole || (prevT !== null && p[0] - prevT > gap)) brk[x] = 1;
        prevT = p[0]; hole = false;
      }
      ctx.strokeStyle = tr.color;
      if (tr.lo != null) { // the envelope
        ctx.globalAlpha = 0.35; ctx.lineWidth = 1; ctx.beginPath();
        for (let x = 0; x < cols; x++) {
          if (isNaN(bmin[x]) || bmax[x] - bmin[x] < (ymax - ymin) / ph) continue;
          ctx.moveTo(L + x + 0.5, Y(bmin[x])); ctx.lineTo(L + x + 0.5, Y(bmax[x]));
        }
        ctx.stroke(); ctx.globalAlpha = 1;
      }
      ctx.lineWidth = tr.dash ? 1.5 : 1.6;
      ctx.setLineDash(tr.dash ? [6, 4] : []);
      ctx.beginPath();
      wraps += tracePath(ctx, X, Y, bval, bt, brk, tr.wrap);
      ctx.stroke();
      ctx.setLineDash([]);
    }
    ctx.restore();
    ctx.strokeStyle = COLORS.line; ctx.strokeRect(L + 0.5, T + 0.5, pw, ph);
    return { shown: last - first, wraps };
  }

  function fixed(v, d) { // no "-0.0"
    const s = v.toFixed(d);
    return Number(s) === 0 ? (0).toFixed(d) : s;
  }
  function fmt(v, d) { return v == null || !isFinite(v) ? "—" : fixed(v, d) + "°"; }
  function fmtRate(v) { return v == null || !isFinite(v) ? "—" : fixed(v, 1) + "°/s"; }
  function wrap180(x) { return ((x + 180) % 360 + 360) % 360 - 180; }

  function setText(id, text) { const el = $(id); if (el.textContent !== text) el.textContent = text; }

  function renderReadouts(last) {
    const tr = last && last.true ? last.true : null;
    for (const k of ["yaw", "pitch", "roll", "heading"]) {
      const v = last ? last[k] : null;
      setText("est-" + k, fmt(v, 1));
      $("est-" + k).dataset.value = v == null ? "" : String(v);
      const tv = tr ? tr[k] : null;
      setText("true-" + k, fmt(tv, 1));
      setText("err-" + k, v != null && tv != null ? fmt(wrap180(v - tv), 2) : "—");
    }
    ["x", "y", "z"].forEach((a, i) => setText("est-rate-" + a, fmtRate(last && last.rate ? last.rate[i] : null)));
    setText("est-t", last && last.t != null ? last.t.toFixed(3) + " s" : "—");
    setText("est-n", last && last.n != null ? "sample " + last.n : "");
  }

  // ---- GNSS: the newest fix attitude-rx reported, and the filter's GNSS flags ------------
  const FIX_WORDS = { none: "no fix", dr: "dead reckoning", "2d": "2D", "3d": "3D", gnss_dr: "3D + dead reckoning",
                      time: "time only" };

  function num(v, d, unit) { return v == null || !isFinite(v) ? "—" : fixed(v, d) + unit; }

  function setQuality(id, q) { const el = $(id); if (el.dataset.quality !== q) el.dataset.quality = q; }

  // the fix's age now: its age on its line plus the source time since that line
  function gnssAge(g, last) {
    if (g.age_s == null) return null;
    const since = last && last.t != null && g.t != null ? last.t - g.t : 0;
    return g.age_s + Math.max(0, since);
  }

  // the filter's GNSS flags, from attitude-rx's flags of the newest sample (--estimator ahrs)
  function gnssAiding() {
    const f = S.counters.filter_flags;
    if (typeof f !== "string") return ["—", ""];
    const names = f.split(" ");
    const aided = names.includes("gnss_aided"), rejected = names.includes("gnss_rejected");
    if (aided && rejected) return ["aided · fix rejected", "bad"];
    if (aided) return ["aided", "ok"];
    if (rejected) return ["fix rejected", "bad"];
    return ["not aided", ""];
  }

  function renderGnss(g, last) {
    const panel = $("gnss-panel");
    if (panel.hidden !== !g) { panel.hidden = !g; S.dirty = true; } // shown once a fix came
    if (!g) return;
    setText("gnss-speed", g.speed == null ? "—" : fixed(g.speed, 2) + " m/s (" + fixed(g.speed * 3.6, 1) + " km/h)");
    setText("gnss-track", num(g.track_deg, 1, "°"));
    setText("gnss-fix", (FIX_WORDS[g.fix] || g.fix) + (g.valid ? ", valid" : ", not valid"));
    setQuality("gnss-fix", g.valid ? "ok" : "bad");
    setText("gnss-sats", g.sats == null ? "—" : String(g.sats));
    setText("gnss-pdop", num(g.pdop, 1, ""));
    setText("gnss-age", num(gnssAge(g, last), 2, " s"));
    const v = g.vel_enu;
    setText("gnss-vel", v ? v.map((x) => num(x, 2, "")).join(", ") + " m/s" : "—");
    const [aiding, q] = gnssAiding();
    setText("gnss-aiding", aiding);
    setQuality("gnss-aiding", q);
    setText("gnss-count", g.count == null ? "—" : String(g.count));
    setText("gnss-source", g.source || "—");
  }

  function draw() {
    const t0 = performance.now();
    const last = S.paused && S.frozen ? S.frozen.last : S.last;
    const vs = viewState();
    let flag = "";
    if (!last) flag = "NO DATA";
    else if (vs === "disconnected") flag = "SERVER LOST";
    else if (vs === "lost") flag = "SOURCE LOST";
    else if (vs === "stalled") flag = "NO DATA";
    drawADI(last, flag);
    drawHSI(last, flag);
    drawAxes3D(last, flag);
    renderReadouts(last);
    const gnss = S.paused && S.frozen ? S.frozen.gnss : S.gnss;
    renderGnss(gnss, last);
    const pts = S.points;
    const tEnd = S.paused && S.frozen ? S.frozen.tEnd : (pts.length ? pts[pts.length - 1][0] : S.windowS);
    const c = S.col;
    if (c.t !== undefined) {
      const hasTruth = pts.length && pts[pts.length - 1][c.true_yaw] != null;
      const ang = [ // yaw and roll in (-180°, 180°], pitch in [-90°, 90°]
        { c: c.yaw, lo: c.yaw_min, hi: c.yaw_max, color: COLORS.yaw, wrap: 180 },
        { c: c.pitch, lo: c.pitch_min, hi: c.pitch_max, color: COLORS.pitch, wrap: 180 },
        { c: c.roll, lo: c.roll_min, hi: c.roll_max, color: COLORS.roll, wrap: 180 },
      ];
      if (hasTruth) {
        ang.push({ c: c.true_yaw, color: COLORS.yaw, dash: true, wrap: 180 },
                 { c: c.true_pitch, color: COLORS.pitch, dash: true, wrap: 180 },
                 { c: c.true_roll, color: COLORS.roll, dash: true, wrap: 180 });
      }
      const drawn = drawChart($("chart-angles"), ang, tEnd, S.windowS);
      drawChart($("chart-rates"), [
        { c: c.rate_x, lo: c.rate_x_min, hi: c.rate_x_max, color: COLORS.yaw },
        { c: c.rate_y, lo: c.rate_y_min, hi: c.rate_y_max, color: COLORS.pitch },
        { c: c.rate_z, lo: c.rate_z_min, hi: c.rate_z_max, color: COLORS.roll },
      ], tEnd, S.windowS);
      if (gnss && c.gnss_speed !== undefined) {
        const sp = drawChart($("chart-gnss-speed"), [{ c: c.gnss_speed, color: COLORS.pitch }], tEnd, S.windowS);
        $("chart-gnss-speed").dataset.points = String(sp.shown);
      }
      $("chart-angles").dataset.points = String(drawn.shown);
      $("chart-angles").dataset.wraps = String(drawn.wraps); // lines broken at ±180° in the last draw
      $("chart-angles").dataset.tEnd = String(tEnd);
      $("chart-angles").dataset.window = String(S.windowS);
    }
    document.body.dataset.drawnPaused = S.paused && S.frozen ? "true" : "false"; // what the last draw showed
    const ms = performance.now() - t0;
    stats.draws += 1;
    stats.lastDrawMs = ms;
    stats.maxDrawMs = Math.max(stats.maxDrawMs, ms);
    drawTimes.push(ms);
    if (drawTimes.length > 200) drawTimes.shift();
  }

  function loop() {
    if (S.dirty) {
      S.dirty = false;
      try { draw(); } catch (e) { console.error(e); }
    }
    requestAnimationFrame(loop);
  }

  new ResizeObserver(() => { S.dirty = true; }).observe(document.querySelector("main"));
  setWindow(S.windowS);
  renderCounters();
  updateStatus();
  connect();
  requestAnimationFrame(loop);
})();
