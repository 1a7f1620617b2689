// sonartrack live console: draws the display updates the server pushes over /ws (plain JS + canvas, no library).
"use strict";
(function () {
  const $ = (id) => document.getElementById(id);
  const S = {                       // everything on screen comes from here; every list is bounded (historyRows)
    historyRows: 3600, btr: [], tracks: [], lofar: new Map(), own: [], targets: null, health: null,
    selected: null, bscan: null, active: null, events: [], drawLog: [], messages: 0, lastMessage: 0, conn: "connecting",
    view: { rows: 240, back: 0 },   // rows shown in the waterfall, and how many rows back from the newest
  };
  const TRACK_COLOURS = ["#ff6b6b", "#4dabf7", "#ffd43b", "#da77f2", "#63e6be", "#ffa94d", "#a9e34b", "#f783ac"];
  const colourOf = (id) => TRACK_COLOURS[((id % TRACK_COLOURS.length) + TRACK_COLOURS.length) % TRACK_COLOURS.length];

  // ---- colour map: black, deep blue, teal, green, yellow, white (a sonar operator's waterfall) --------------
  const LUT = (() => {
    const stops = [[0, 0, 0, 0], [0.22, 8, 30, 90], [0.45, 0, 120, 130], [0.65, 40, 200, 80],
      [0.85, 240, 230, 60], [1, 255, 255, 255]];
    const lut = new Uint8ClampedArray(256 * 3);
    for (let i = 0; i < 256; i++) {
      const f = i / 255; let k = 0;
      while (k < stops.length - 2 && f > stops[k + 1][0]) k++;
      const [f0, ...c0] = stops[k], [f1, ...c1] = stops[k + 1], u = (f - f0) / (f1 - f0);
      for (let j = 0; j < 3; j++) lut[i * 3 + j] = c0[j] + u * (c1[j] - c0[j]);
    }
    return lut;
  })();

  // colour range from the data on screen: 2nd and 99.7th percentiles of a sample of the visible values
  function range(rows, key) {
    const vals = [];
    let n = 0; for (const r of rows) n += r[key].length;
    const step = Math.max(1, Math.floor(n / 20000));
    let i = 0;
    for (const r of rows) for (const v of r[key]) { if (i++ % step === 0 && v !== null) vals.push(v); }
    if (!vals.length) return [0, 1];
    vals.sort((a, b) => a - b);
    const lo = vals[Math.floor(0.02 * (vals.length - 1))], hi = vals[Math.floor(0.997 * (vals.length - 1))];
    return hi > lo ? [lo, hi] : [lo - 1, lo + 1];
  }

  function fitCanvas(c) {
    const r = c.getBoundingClientRect(), d = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(r.width * d)), h = Math.max(1, Math.round(r.height * d));
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
    const g = c.getContext("2d"); g.setTransform(d, 0, 0, d, 0, 0);
    return { g, w: r.width, h: r.height };
  }

  // an image (rows newest first, one pixel per bin) in the colour map, drawn into box (x, y, w, h)
  function drawImage(g, rows, key, lo, hi, box) {
    const nb = rows.reduce((m, r) => Math.max(m, r[key].length), 0);
    if (!nb || !rows.length) return;
    const img = new ImageData(nb, rows.length), px = img.data, scale = 255 / (hi - lo);
    rows.forEach((r, y) => {
      const v = r[key];
      for (let b = 0; b < nb; b++) {
        const o = (y * nb + b) * 4, x = v[b];
        if (x === null || x === undefined) { px[o + 3] = 255; continue; }
        const k = Math.max(0, Math.min(255, Math.round((x - lo) * scale))) * 3;
        px[o] = LUT[k]; px[o + 1] = LUT[k + 1]; px[o + 2] = LUT[k + 2]; px[o + 3] = 255;
      }
    });
    const off = document.createElement("canvas"); off.width = nb; off.height = rows.length;
    off.getContext("2d").putImageData(img, 0, 0);
    g.imageSmoothingEnabled = false;
    g.drawImage(off, box.x, box.y, box.w, box.h);
  }

  function scaleText(el, lo, hi) { el.textContent = `${lo.toFixed(0)} … ${hi.toFixed(0)} dB`; }
  const clock = (t) => {
    if (t === null || t === undefined || !isFinite(t)) return "--:--:--";
    const s = Math.max(0, Math.floor(t)); const p = (n) => String(n).padStart(2, "0");
    return `${p(Math.floor(s / 3600))}:${p(Math.floor(s / 60) % 60)}:${p(s % 60)}`;
  };

  // ---- waterfall ---------------------------------------------------------------------------------------------
  const M = { l: 44, r: 10, t: 8, b: 22 };  // plot margins (px)
  let btrGeom = null;                       // what the last drawing mapped where (for clicks and the tests)

  function visibleBtr() {
    const n = S.btr.length, end = Math.max(0, n - 1 - S.view.back), start = Math.max(0, end - S.view.rows + 1);
    return S.btr.slice(start, end + 1).reverse();   // newest first
  }

  function coneFrac(cones, c) {             // cone angle -> fraction of the image width (bins may be uneven)
    const n = cones.length;
    if (n < 2) return 0.5;
    if (c <= cones[0]) return 0.5 / n;
    for (let i = 1; i < n; i++) if (c <= cones[i]) {
      return (i - 1 + (c - cones[i - 1]) / (cones[i] - cones[i - 1]) + 0.5) / n;
    }
    return 1 - 0.5 / n;
  }

  function drawBtr() {
    const { g, w, h } = fitCanvas($("btr"));
    g.fillStyle = "#000"; g.fillRect(0, 0, w, h);
    const rows = visibleBtr();
    const box = { x: M.l, y: M.t, w: w - M.l - M.r, h: h - M.t - M.b };
    if (!rows.length) { btrGeom = null; return label(g, "waiting for the first bearing-time row…", w / 2, h / 2); }
    const [lo, hi] = range(rows, "level_db"); scaleText($("btr-scale"), lo, hi);
    const imgH = Math.min(box.h, rows.length * (box.h / S.view.rows));
    drawImage(g, rows, "level_db", lo, hi, { x: box.x, y: box.y, w: box.w, h: imgH });
    const cones = rows[0].cone_deg, tTop = rows[0].t_s, dt = rows.length > 1 ? (tTop - rows[rows.length - 1].t_s) /
      (rows.length - 1) : 1;
    const geom = { box, cones, tTop, dt: dt || 1, rowH: box.h / S.view.rows, tBottom: tTop - S.view.rows * (dt || 1) };
    geom.x = (c) => box.x + coneFrac(cones, c) * box.w;
    geom.y = (t) => box.y + (tTop - t) / geom.dt * geom.rowH + geom.rowH / 2;
    btrGeom = geom;
    axesBtr(g, geom);
    overlayTracks(g, geom);
  }

  function axesBtr(g, geom) {
    const { box } = geom;
    g.strokeStyle = "#2b3d4a"; g.fillStyle = "#7f95a3"; g.font = "10px monospace"; g.lineWidth = 1;
    g.textAlign = "center"; g.textBaseline = "top";
    for (let c = 0; c <= 180; c += 30) {
      const x = geom.x(c); g.beginPath(); g.moveTo(x, box.y + box.h); g.lineTo(x, box.y + box.h + 4); g.stroke();
      g.fillText(`${c}°`, x, box.y + box.h + 6);
    }
    g.textAlign = "right"; g.textBaseline = "middle";
    const span = S.view.rows * geom.dt, step = niceStep(span / 6);
    for (let t = Math.floor(geom.tTop / step) * step; t > geom.tBottom && t >= 0; t -= step) {
      const y = geom.y(t); if (y < box.y || y > box.y + box.h) continue;
      g.fillText(clock(t).slice(span < 3600 ? 3 : 0), box.x - 4, y);
      g.beginPath(); g.moveTo(box.x - 3, y); g.lineTo(box.x, y); g.stroke();
    }
    g.strokeRect(box.x + 0.5, box.y + 0.5, box.w - 1, box.h - 1);
  }

  function niceStep(x) {
    const p = Math.pow(10, Math.floor(Math.log10(Math.max(x, 1e-9)))), f = x / p;
    return (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10) * p;
  }

  function trackPaths(geom) {     // id -> {status, pts: [[x, y], ...] newest first} within the visible time span
    const paths = new Map();
    for (let i = S.tracks.length - 1; i >= 0; i--) {
      const m = S.tracks[i];
      if (m.t_s > geom.tTop + geom.dt / 2) continue;
      if (m.t_s < geom.tBottom) break;
      for (const tr of m.tracks) {
        if (tr.cone_deg === null) continue;
        if (!paths.has(tr.id)) paths.set(tr.id, { status: tr.status, pts: [] });
        paths.get(tr.id).pts.push([geom.x(tr.cone_deg), geom.y(m.t_s)]);
      }
    }
    return paths;
  }

  function overlayTracks(g, geom) {
    const paths = trackPaths(geom);
    geom.paths = paths;
    for (const [id, p] of paths) {
      const sel = id === S.selected, col = sel ? "#ffe14d" : colourOf(id);
      g.strokeStyle = col; g.globalAlpha = p.status === "confirmed" ? 1 : 0.5;
      let lastY = -1e9;                     // brackets either side of the trace, so the trace itself stays visible
      g.beginPath();
      for (const [x, y] of p.pts) {
        if (Math.abs(y - lastY) < 16) continue;
        lastY = y; g.moveTo(x - 18, y); g.lineTo(x - 8, y); g.moveTo(x + 8, y); g.lineTo(x + 18, y);
      }
      const a = g.globalAlpha;
      g.strokeStyle = "#000"; g.lineWidth = sel ? 6 : 5; g.stroke();        // a dark edge: visible on any colour
      g.strokeStyle = col; g.lineWidth = sel ? 3.5 : 2.5; g.globalAlpha = a; g.stroke(); g.globalAlpha = 1;
      const [x0, y0] = p.pts[0];
      g.font = sel ? "bold 12px monospace" : "11px monospace"; g.textAlign = "left"; g.textBaseline = "top";
      g.fillStyle = "rgba(0,0,0,0.65)"; g.fillRect(x0 + 4, y0 + 2, 8 + 7 * String(id).length, 14);
      g.fillStyle = col; g.fillText(`T${id}`, x0 + 5, y0 + 3);
    }
  }

  function label(g, text, x, y) {
    g.fillStyle = "#5f7584"; g.font = "12px monospace"; g.textAlign = "center"; g.textBaseline = "middle";
    g.fillText(text, x, y);
  }

  // ---- LOFAR -------------------------------------------------------------------------------------------------
  function drawLofar() {
    const { g, w, h } = fitCanvas($("lofar"));
    g.fillStyle = "#000"; g.fillRect(0, 0, w, h);
    const all = S.selected === null ? [] : (S.lofar.get(S.selected) || []);
    $("lofar-title").textContent = S.selected === null ? "click a trace or a table row" : `track T${S.selected}`;
    const box = { x: M.l, y: M.t, w: w - M.l - M.r, h: h - M.t - M.b };
    const nShow = Math.max(20, Math.round(box.h / 2)), rows = all.slice(-nShow).reverse();
    if (!rows.length) {
      return label(g, S.selected === null ? "no trace selected" : "waiting for LOFAR rows of this track…", w / 2, h / 2);
    }
    const [lo, hi] = range(rows, "level_db"); scaleText($("lofar-scale"), lo, hi);
    drawImage(g, rows, "level_db", lo, hi, { x: box.x, y: box.y, w: box.w, h: box.h * rows.length / nShow });
    const f = rows[0].freq_hz, f0 = f[0], f1 = f[f.length - 1];
    g.fillStyle = "#7f95a3"; g.strokeStyle = "#2b3d4a"; g.font = "10px monospace"; g.textAlign = "center";
    g.textBaseline = "top";
    const step = niceStep((f1 - f0) / 6);
    for (let x = Math.ceil(f0 / step) * step; x <= f1; x += step) {
      g.fillText(`${x}`, box.x + (x - f0) / (f1 - f0) * box.w, box.y + box.h + 6);
    }
    g.textAlign = "right"; g.textBaseline = "middle";
    g.fillText("Hz", box.x - 4, box.y + box.h + 11);
    g.fillText(clock(rows[0].t_s).slice(3), box.x - 4, box.y + 6);
    g.strokeRect(box.x + 0.5, box.y + 0.5, box.w - 1, box.h - 1);
  }

  // ---- tactical plot -----------------------------------------------------------------------------------------
  function tacBounds() {
    const xs = [], ys = [];
    const add = (x, y) => { if (x !== null && y !== null && isFinite(x) && isFinite(y)) { xs.push(x); ys.push(y); } };
    S.own.slice(-600).forEach((o) => add(o.x_m, o.y_m));
    // only positions with a determined range: an undetermined one is a bearing line, its x, y meaningless
    for (const r of allTargets()) {
      if (r.range_m === null || r.range_m === undefined || r.reason) continue;
      add(r.x_m, r.y_m); if (r.mirror) add(r.mirror.x_m, r.mirror.y_m);
    }
    if (!xs.length) return null;
    let x0 = Math.min(...xs), x1 = Math.max(...xs), y0 = Math.min(...ys), y1 = Math.max(...ys);
    const pad = Math.max(500, 0.12 * Math.max(x1 - x0, y1 - y0));
    return [x0 - pad, x1 + pad, y0 - pad, y1 + pad];
  }

  function drawTac() {
    const { g, w, h } = fitCanvas($("tac"));
    g.fillStyle = "#02070a"; g.fillRect(0, 0, w, h);
    const b = tacBounds();
    if (!b) return label(g, "waiting for navigation…", w / 2, h / 2);
    const s = Math.min(w / (b[1] - b[0]), h / (b[3] - b[2])), cx = (b[0] + b[1]) / 2, cy = (b[2] + b[3]) / 2;
    const P = (x, y) => [w / 2 + (x - cx) * s, h / 2 - (y - cy) * s];
    const own = S.own[S.own.length - 1];
    rings(g, P, own, s, w, h);
    g.strokeStyle = "#3d5566"; g.lineWidth = 1; g.beginPath();
    S.own.slice(-1200).forEach((o, k) => { const [x, y] = P(o.x_m, o.y_m); k ? g.lineTo(x, y) : g.moveTo(x, y); });
    g.stroke();
    for (const r of allTargets()) drawTarget(g, P, r, own);
    if (own) drawOwnship(g, P, own);
  }

  function rings(g, P, own, s, w, h) {
    if (!own) return;
    const step = niceStep(Math.max(w, h) / s / 6), [ox, oy] = P(own.x_m, own.y_m);
    g.strokeStyle = "#12303a"; g.fillStyle = "#3b6270"; g.font = "10px monospace"; g.textAlign = "left";
    for (let r = step, k = 0; r * s < Math.max(w, h) * 1.5 && k < 12; r += step, k++) {
      g.beginPath(); g.arc(ox, oy, r * s, 0, 2 * Math.PI); g.stroke();
      g.fillText(r >= 1000 ? `${r / 1000} km` : `${r} m`, ox + r * s * 0.7071 + 3, oy - r * s * 0.7071);
    }
    $("tac-scale").textContent = `rings ${step >= 1000 ? step / 1000 + " km" : step + " m"} · north up`;
  }

  function drawOwnship(g, P, o) {
    if (o.array) {
      g.strokeStyle = "#ff9f43"; g.lineWidth = 3; g.beginPath();
      o.array.forEach(([x, y], k) => { const [u, v] = P(x, y); k ? g.lineTo(u, v) : g.moveTo(u, v); });
      g.stroke();
    }
    const [x, y] = P(o.x_m, o.y_m), a = ((o.heading_deg ?? 0) * Math.PI) / 180;
    g.save(); g.translate(x, y); g.rotate(a);
    g.fillStyle = "#e3eef5"; g.beginPath(); g.moveTo(0, -9); g.lineTo(6, 7); g.lineTo(-6, 7); g.closePath(); g.fill();
    g.restore();
  }

  // passive targets (ids T1..) then the active chain's (A1..: a mirror pair each until its side is decided)
  function allTargets() {
    const passive = S.targets ? S.targets.rows : [];
    return passive.concat((S.active ? S.active.rows : []).map((r) => Object.assign({ active: true }, r)));
  }
  const tag = (r) => `${r.active ? "A" : "T"}${r.id}`;

  function drawTarget(g, P, r, own) {
    const col = !r.active && r.id === S.selected ? "#ffe14d" : colourOf(r.id);
    g.strokeStyle = col; g.fillStyle = col; g.lineWidth = 1.2;
    if (r.x_m === null || r.y_m === null || r.x_m === undefined) {        // range not determined: a bearing line
      if (!own || r.bearing_deg === null) return;
      const [ox, oy] = P(own.x_m, own.y_m), a = (r.bearing_deg * Math.PI) / 180;
      g.setLineDash([6, 4]); g.globalAlpha = 0.7; g.beginPath(); g.moveTo(ox, oy);
      g.lineTo(ox + 4000 * Math.sin(a), oy - 4000 * Math.cos(a)); g.stroke(); g.setLineDash([]); g.globalAlpha = 1;
      g.font = "11px monospace"; g.fillText(`${tag(r)}?`, ox + 60 * Math.sin(a) + 4, oy - 60 * Math.cos(a));
      return;
    }
    if (r.ellipse && r.ellipse.length > 2) {
      g.globalAlpha = 0.15; g.beginPath();
      r.ellipse.forEach(([x, y], k) => { const [u, v] = P(x, y); k ? g.lineTo(u, v) : g.moveTo(u, v); });
      g.closePath(); g.fill(); g.globalAlpha = 0.8; g.stroke(); g.globalAlpha = 1;
    }
    for (const leg of r.legs || []) drawLeg(g, P, leg, col);
    const [x, y] = P(r.x_m, r.y_m);
    if (r.mirror && r.mirror.x_m !== null) {                              // the rejected mirror: dotted
      const [mx, my] = P(r.mirror.x_m, r.mirror.y_m);
      g.setLineDash([2, 3]); g.globalAlpha = 0.6; g.beginPath(); g.arc(mx, my, 5, 0, 2 * Math.PI); g.stroke();
      g.beginPath(); g.moveTo(mx, my); g.lineTo(x, y); g.stroke(); g.setLineDash([]); g.globalAlpha = 1;
    }
    if (r.course_deg !== null && r.speed_mps !== null && r.course_deg !== undefined) {   // 5-minute speed leader
      const a = (r.course_deg * Math.PI) / 180, d = r.speed_mps * 300;
      const [u, v] = P(r.x_m + d * Math.sin(a), r.y_m + d * Math.cos(a));
      g.beginPath(); g.moveTo(x, y); g.lineTo(u, v); g.stroke();
    }
    g.beginPath(); g.arc(x, y, 4, 0, 2 * Math.PI); g.fill();
    g.font = "bold 11px monospace"; g.textAlign = "left"; g.textBaseline = "bottom"; g.fillText(tag(r), x + 6, y - 3);
  }

  function drawLeg(g, P, leg, col) {        // a leg: [[x, y], ...] or {points: [...]} or {x_m: [...], y_m: [...]}
    let pts = Array.isArray(leg) ? leg : leg.points;
    if (!pts && leg.x_m && leg.y_m && Array.isArray(leg.x_m)) pts = leg.x_m.map((x, k) => [x, leg.y_m[k]]);
    if (!pts || pts.length < 2) return;
    g.strokeStyle = col; g.globalAlpha = 0.5; g.setLineDash([8, 3]); g.beginPath();
    pts.forEach(([x, y], k) => { const [u, v] = P(x, y); k ? g.lineTo(u, v) : g.moveTo(u, v); });
    g.stroke(); g.setLineDash([]); g.globalAlpha = 1;
  }

  // ---- B-scan (active pings): bearing across, range up -------------------------------------------------------
  function drawBscan() {
    const c = $("bscan");
    if (!S.bscan) return;
    c.hidden = false; $("side-title").textContent = `B-scan · ping ${clock(S.bscan.t_s)} · events`;
    const { g, w, h } = fitCanvas(c);
    g.fillStyle = "#000"; g.fillRect(0, 0, w, h);
    const lv = S.bscan.level_db || [], br = S.bscan.bearing_deg || [], rg = S.bscan.range_m || [];
    if (!lv.length) return;
    const rows = [];                        // image rows = ranges, far at the top; columns = bearings
    for (let k = rg.length - 1; k >= 0; k--) rows.push({ v: lv.map((col) => col[k]) });
    const [lo, hi] = range(rows, "v");
    const box = { x: M.l, y: M.t, w: w - M.l - M.r, h: h - M.t - M.b };
    drawImage(g, rows, "v", lo, hi, box);
    g.fillStyle = "#7f95a3"; g.font = "10px monospace"; g.textAlign = "center"; g.textBaseline = "top";
    g.fillText(`${num(br[0])}°`, box.x, box.y + box.h + 4);
    g.fillText(`${num(br[br.length - 1])}°`, box.x + box.w, box.y + box.h + 4);
    g.textAlign = "right"; g.fillText(`${(rg[rg.length - 1] / 1000).toFixed(1)} km`, box.x - 3, box.y);
    bscanTracks(g, box, br, rg);
  }

  // the scan's tracks where their echoes fall: cone angle across, half the bistatic path up (A<id>: active ids)
  let bscanDrawn = [];
  function bscanTracks(g, box, br, rg) {
    bscanDrawn = [];
    const r0 = rg[0], r1 = rg[rg.length - 1];
    if (!(r1 > r0)) return;
    for (const t of S.bscan.tracks || []) {
      if (t.range_m < r0 || t.range_m > r1 || t.cone_deg === null) continue;
      const x = box.x + coneFrac(br, t.cone_deg) * box.w, y = box.y + (1 - (t.range_m - r0) / (r1 - r0)) * box.h;
      const conf = t.status === "confirmed", col = colourOf(t.id);
      g.globalAlpha = conf ? 1 : 0.5; g.lineWidth = conf ? 2 : 1;
      g.strokeStyle = "#000"; g.beginPath(); g.arc(x, y, 7, 0, 2 * Math.PI); g.stroke();
      g.strokeStyle = col; g.beginPath(); g.arc(x, y, 6, 0, 2 * Math.PI); g.stroke();
      if (conf) {
        g.font = "bold 11px monospace"; g.textAlign = "left"; g.textBaseline = "bottom"; g.fillStyle = col;
        g.fillText(`A${t.id}`, x + 8, y - 4);
      }
      g.globalAlpha = 1;
      bscanDrawn.push(t.id);
    }
  }

  // ---- table, health, events ---------------------------------------------------------------------------------
  const num = (v, d = 0) => (v === null || v === undefined || !isFinite(v) ? "—" : Number(v).toFixed(d));

  function drawTable() {
    const body = $("targets").tBodies[0];
    const rows = allTargets(), at = S.targets || S.active;
    $("tbl-time").textContent = at ? `solution at ${clock(at.t_s)}` : "";
    body.replaceChildren(...rows.map((r) => {
      const tr = document.createElement("tr");
      tr.dataset.id = r.id; if (!r.active && r.id === S.selected) tr.className = "sel";
      if (r.active) tr.classList.add("active");
      const side = r.active && r.side === "undecided" ? "undecided pair" : (r.side ?? "—");
      const cells = [
        `<span class="sw" style="background:${colourOf(r.id)}"></span>${tag(r)}`, esc(side),
        `${num(r.bearing_deg, 1)}°`,
        r.range_m === null || r.range_m === undefined ? null
          : `${num(r.range_m / 1000, 2)} ± ${num((r.range_sd_m ?? NaN) / 1000, 2)} km`,
        r.course_deg === null || r.course_deg === undefined ? "—"
          : `${num(r.course_deg, 0)}° / ${num((r.speed_mps ?? NaN) * 1.943844, 1)} kn`,
        r.tonal_hz === null || r.tonal_hz === undefined ? "—" : `${num(r.tonal_hz, 1)} Hz`];
      tr.innerHTML = cells.map((c, k) => (c === null
        ? `<td class="why">${esc(r.reason || "range not determined")}</td>`
        : `<td class="${k >= 2 ? "num" : ""}">${c}</td>`)).join("");
      if (!r.active) tr.addEventListener("click", () => select(r.id));   // the LOFAR is a passive track's
      return tr;
    }));
  }

  function esc(s) {
    return String(s).replace(/[&<>"']/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" }[c]));
  }

  function drawHealth() {
    const hm = S.health;
    $("h-msgs").textContent = S.messages;
    const conn = $("conn"); conn.dataset.state = S.conn;
    conn.textContent = { live: "LIVE", connecting: "CONNECTING", down: "RECONNECTING" }[S.conn];
    const tNow = S.btr.length ? S.btr[S.btr.length - 1].t_s : S.bscan ? S.bscan.t_s : hm ? hm.t_s : null;
    $("h-time").textContent = clock(tNow);
    if (!hm) return;
    $("h-rate").textContent = hm.rate_hz ? `${num(hm.rate_hz / 1000, 2)} kHz` : "—";
    $("h-lat").textContent = hm.latency_s === null || hm.latency_s === undefined ? "—" : `${num(hm.latency_s, 2)} s`;
    $("h-gaps").textContent = num(hm.gaps);
    const nav = $("h-nav"); nav.dataset.state = hm.nav || "unknown";
    nav.textContent = hm.nav === "coasting" ? "NAV COASTING" : hm.nav === "ok" ? "NAV OK" : "NAV --";
  }

  function addEvents(t, list) {
    for (const e of list || []) S.events.push({ t, text: String(e) });
    if (S.events.length > 200) S.events.splice(0, S.events.length - 200);
    const ol = $("events");
    ol.replaceChildren(...S.events.slice(-60).reverse().map((e) => {
      const li = document.createElement("li");
      if (/gap|late|bad|dropout|disconnect|coast/i.test(e.text)) li.className = "warn";
      li.innerHTML = `${clock(e.t)} <b>${esc(e.text)}</b>`;
      return li;
    }));
    if (S.events.length) $("h-event").textContent = S.events[S.events.length - 1].text;
  }

  // ---- updates -----------------------------------------------------------------------------------------------
  const cap = (a, n) => { if (a.length > n) a.splice(0, a.length - n); };

  function apply(m) {
    switch (m.type) {
      case "hello": S.historyRows = m.history_rows; break;
      case "history": reset(); m.updates.forEach(apply); break;
      case "btr":                         // scrolled back in history, the picture stays put while rows arrive
        S.btr.push(m); cap(S.btr, S.historyRows);
        if (S.view.back > 0) S.view.back = Math.min(S.btr.length - 1, S.view.back + 1);
        break;
      case "tracks": S.tracks.push(m); cap(S.tracks, S.historyRows); break;
      case "lofar": {
        if (!S.lofar.has(m.track)) S.lofar.set(m.track, []);
        const a = S.lofar.get(m.track); a.push(m); cap(a, S.historyRows);
        if (S.lofar.size > 64) S.lofar.delete(S.lofar.keys().next().value);
        break;
      }
      case "ownship": S.own.push(m); cap(S.own, S.historyRows); break;
      case "targets": S.targets = m; break;
      case "health": S.health = m; addEvents(m.t_s, m.events); break;
      case "selected": S.selected = m.track; break;
      case "bscan": S.bscan = m; break;
      case "active_targets": S.active = m; break;
      case "error": addEvents(null, [`server: ${m.detail}`]); break;
      default: break;
    }
  }

  function reset() {
    Object.assign(S, { btr: [], tracks: [], lofar: new Map(), own: [], targets: null, health: null, bscan: null,
      active: null, events: [] });
  }

  let dirty = false;
  function redraw() {
    if (dirty) return;
    dirty = true;
    requestAnimationFrame(() => {
      dirty = false;
      try { drawBtr(); drawLofar(); drawTac(); drawTable(); drawHealth(); drawBscan(); } catch (e) { console.error(e); throw e; }
      if (S.btr.length) {                   // when each row reached the screen (benchmarks/bench_console.py)
        S.drawLog.push([S.btr[S.btr.length - 1].t_s, Date.now()]); cap(S.drawLog, 4000);
      }
    });
  }

  // ---- the WebSocket: reconnects with backoff, the server replays its history on every connection -----------
  let ws = null, retry = 0;
  function connect() {
    const proto = location.protocol === "https:" ? "wss:" : "ws:";
    ws = new WebSocket(`${proto}//${location.host}/ws`);
    ws.onopen = () => { S.conn = "live"; retry = 0; redraw(); };
    ws.onmessage = (ev) => {
      S.messages++; S.lastMessage = performance.now();
      apply(JSON.parse(ev.data)); redraw();
    };
    ws.onclose = () => {
      S.conn = "down"; redraw();
      setTimeout(connect, Math.min(5000, 300 * Math.pow(2, retry++)));
    };
  }

  function select(id) {
    S.selected = id; redraw();
    if (ws && ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify({ select: id }));
  }

  // click on the waterfall: the nearest track point within 14 px
  function pickTrack(px, py) {
    if (!btrGeom || !btrGeom.paths) return null;
    let best = null, bestD = 14 * 14;
    for (const [id, p] of btrGeom.paths) {
      for (const [x, y] of p.pts) {
        const d = (x - px) ** 2 + (y - py) ** 2;
        if (d < bestD) { bestD = d; best = id; }
      }
    }
    return best;
  }

  $("btr").addEventListener("click", (ev) => {
    const r = ev.target.getBoundingClientRect(), id = pickTrack(ev.clientX - r.left, ev.clientY - r.top);
    if (id !== null) select(id);
  });
  $("btr").addEventListener("wheel", (ev) => {
    ev.preventDefault();
    if (ev.ctrlKey) zoom(ev.deltaY > 0 ? 1.25 : 0.8);
    else { S.view.back = Math.max(0, Math.min(S.btr.length - 1, S.view.back + Math.round(ev.deltaY / 4))); follow(); }
    redraw();
  }, { passive: false });
  function zoom(f) { S.view.rows = Math.max(30, Math.min(S.historyRows, Math.round(S.view.rows * f))); redraw(); }
  function follow() { $("go-live").classList.toggle("on", S.view.back === 0); }
  $("zoom-out").addEventListener("click", () => zoom(1.5));
  $("zoom-in").addEventListener("click", () => zoom(1 / 1.5));
  $("go-live").addEventListener("click", () => { S.view.back = 0; follow(); redraw(); });
  new ResizeObserver(redraw).observe(document.querySelector("main"));

  // for the browser test: read-only views of what is on screen
  window.sonarConsole = {
    state: S,
    trackPoint(id) {                        // page coordinates of the newest drawn point of track id
      if (!btrGeom || !btrGeom.paths || !btrGeom.paths.has(id)) return null;
      const [x, y] = btrGeom.paths.get(id).pts[0], r = $("btr").getBoundingClientRect();
      return { x: r.left + x, y: r.top + y };
    },
    drawnTracks() { return btrGeom && btrGeom.paths ? [...btrGeom.paths.keys()] : []; },
    bscanTracks() { return bscanDrawn.slice(); },   // active track ids drawn over the B-scan
  };
  connect();
})();
