// The page of animation.html (animation.cc puts the run's data in place of the marker
// /*FIVEBAR_DATA*/null). Self-contained: inline style and script, a canvas, no network.
//
// The page honours a URL fragment #t=SECONDS (shows that time, paused). It records how it went
// in <body data-status>: "ok" once drawn, "error: <message>" after a script error (the test
// reads it with chromium --dump-dom).
#pragma once

namespace fivebar::io {

inline constexpr char kAnimationPage[] = R"page(<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>fivebar animation</title>
<style>
body { font: 14px sans-serif; margin: 10px; color: #222; background: #fff; }
#wrap { max-width: 980px; }
h1 { font-size: 17px; margin: 0 0 6px 0; }
canvas { border: 1px solid #ccc; width: 100%; height: auto; display: block; }
#controls { display: flex; gap: 10px; align-items: center; margin: 6px 0; }
#slider { flex: 1; }
#readout { font-family: monospace; white-space: pre-wrap; font-size: 13px; }
#note { color: #555; font-size: 12px; }
</style>
</head>
<body data-status="loading">
<div id="wrap">
<h1 id="title">fivebar</h1>
<canvas id="view" width="960" height="560"></canvas>
<div id="controls">
  <button id="play" type="button">Play</button>
  <input id="slider" type="range" min="0" max="0" step="1" value="0">
  <label>speed <select id="speed">
    <option>0.05</option><option>0.1</option><option>0.25</option><option>0.5</option>
    <option selected>1</option><option>2</option><option>4</option>
  </select> x</label>
</div>
<div id="readout"></div>
<p id="note"></p>
</div>
<script>
"use strict";
window.addEventListener("error", function (e) {
  document.body.dataset.status = "error: " + e.message;
});
const DATA = /*FIVEBAR_DATA*/null;
(function () {
  const m = DATA.motion, gh = DATA.ghost, g = DATA.geometry;
  const n = m.t.length;
  const canvas = document.getElementById("view"), ctx = canvas.getContext("2d");
  const W = canvas.width, H = canvas.height, PANEL = 230;  // drawing | legend panel
  const FOUR = g.type === "four_bar";  // crank O-B, coupler B-C, rocker D0-C; one drive
  const LINKS = FOUR
    ? [["crank O-B", "#1f77b4", "O", "B"], ["coupler B-C", "#2ca02c", "B", "C"],
       ["rocker D0-C", "#ff7f0e", "D0", "C"]]
    : [["crank O-B", "#1f77b4", "O", "B"], ["crank D0-D", "#ff7f0e", "D0", "D"],
       ["coupler B-C", "#2ca02c", "B", "C"], ["coupler D-C", "#9467bd", "D", "C"]];
  const JOINTS = FOUR ? ["O", "B", "C", "D0"] : ["O", "B", "C", "D", "D0"];
  const POWERS = JOINTS.map(function (k, j) { return m["p" + (j + 1)]; });
  const VIRIDIS = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];

  function pose(tr, i) {
    const th = LINKS.map(function (L, j) { return tr["th" + (j + 1)][i]; });
    if (th.some(function (v) { return v === null; })) return null;
    const e = th.map(function (a) { return [Math.cos(a), Math.sin(a)]; });
    const B = [g.l[0] * e[0][0], g.l[0] * e[0][1]];
    if (FOUR) {  // th: crank, coupler B->C, rocker D0->C
      return { O: [0, 0], D0: [g.l0, 0], B: B,
               C: [B[0] + g.l[1] * e[1][0], B[1] + g.l[1] * e[1][1]],
               P: [B[0] + g.lp * e[1][0], B[1] + g.lp * e[1][1]], th3: th[1] };
    }
    const D = [g.l0 + g.l[1] * e[1][0], g.l[1] * e[1][1]];
    return { O: [0, 0], D0: [g.l0, 0], B: B, D: D,
             C: [B[0] + g.l[2] * e[2][0], B[1] + g.l[2] * e[2][1]],
             P: [B[0] + g.lp * e[2][0], B[1] + g.lp * e[2][1]], th3: th[2] };
  }
  function maxAbs(a) {
    let v = 0;
    for (const x of a) if (x !== null && Math.abs(x) > v) v = Math.abs(x);
    return v;
  }
  // the colour scale: square root of the power (it spans orders of magnitude), ending at the
  // 98th percentile of the joints' powers (a brief spike would leave every other frame dark);
  // larger values get the top colour
  const pPeak = Math.max.apply(null, POWERS.map(maxAbs));
  const pAll = [].concat.apply([], POWERS).filter(function (v) { return v !== null; })
    .sort(function (a, b) { return a - b; });
  const pMax = pAll[Math.floor(0.98 * (pAll.length - 1))] || pPeak || 1;
  const mMax = Math.max(maxAbs(m.M1), m.M2 ? maxAbs(m.M2) : 0) || 1, m3Max = maxAbs(m.M3) || 1;
  const fMax = maxAbs(m.F);
  const lMax = Math.max.apply(null, [g.l0].concat(g.l)), arrowLen = 0.3 * lMax;

  // the box around every pose of both tracks (and the force arrow), in true proportions
  let box = [Infinity, Infinity, -Infinity, -Infinity];
  function grow(p, r) {
    box = [Math.min(box[0], p[0] - r), Math.min(box[1], p[1] - r),
           Math.max(box[2], p[0] + r), Math.max(box[3], p[1] + r)];
  }
  [m, gh].forEach(function (tr) {
    if (!tr) return;
    for (let i = 0; i < tr.t.length; ++i) {
      const q = pose(tr, i);
      if (!q) continue;
      JOINTS.forEach(function (k) { grow(q[k], 0); });
      grow(q.P, tr === m && fMax > 0 ? arrowLen : 0);
    }
  });
  const pad = 0.06 * Math.max(box[2] - box[0], box[3] - box[1]) + 1e-9;
  box = [box[0] - pad, box[1] - pad, box[2] + pad, box[3] + pad];
  const scale = Math.min((W - PANEL - 20) / (box[2] - box[0]), (H - 40) / (box[3] - box[1]));
  const ox = 10 + 0.5 * (W - PANEL - 20 - scale * (box[2] - box[0]));
  const oy = 30 + 0.5 * (H - 40 - scale * (box[3] - box[1]));
  function X(p) { return [ox + (p[0] - box[0]) * scale, oy + (box[3] - p[1]) * scale]; }

  function colour(v) {  // viridis of sqrt(v), v in [0, 1]
    const x = Math.sqrt(Math.min(Math.max(v, 0), 1)) * (VIRIDIS.length - 1);
    const k = Math.min(Math.floor(x), VIRIDIS.length - 2);
    const f = x - k, a = VIRIDIS[k], b = VIRIDIS[k + 1];
    const rgb = [0, 1, 2].map(function (c) { return Math.round(a[c] + f * (b[c] - a[c])); });
    return "rgb(" + rgb.join(",") + ")";
  }
  function fmt(x, d) { return x === null ? "-" : Number(x).toPrecision(d || 4); }
  function index(tr, t) {  // last sample at or before t
    let lo = 0, hi = tr.t.length - 1;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (tr.t[mid] <= t) lo = mid; else hi = mid - 1;
    }
    return lo;
  }
  function line(a, b, style, width, dash) {
    ctx.strokeStyle = style; ctx.lineWidth = width; ctx.setLineDash(dash || []);
    ctx.beginPath(); ctx.moveTo(a[0], a[1]); ctx.lineTo(b[0], b[1]); ctx.stroke();
    ctx.setLineDash([]);
  }
  function arrowHead(tip, angle, size, style) {
    ctx.fillStyle = style; ctx.beginPath(); ctx.moveTo(tip[0], tip[1]);
    ctx.lineTo(tip[0] - size * Math.cos(angle - 0.4), tip[1] - size * Math.sin(angle - 0.4));
    ctx.lineTo(tip[0] - size * Math.cos(angle + 0.4), tip[1] - size * Math.sin(angle + 0.4));
    ctx.closePath(); ctx.fill();
  }
  function torqueArc(c, value, max, style, label) {  // counter-clockwise positive
    if (value === null || value === 0) return;
    const r = 24, sweep = Math.max(0.15, Math.min(1, Math.abs(value) / max)) * 1.6 * Math.PI;
    const ccw = value > 0, end = ccw ? -sweep : sweep;  // screen y points down
    ctx.strokeStyle = style; ctx.lineWidth = 2.5;
    ctx.beginPath(); ctx.arc(c[0], c[1], r, 0, end, ccw); ctx.stroke();
    const tip = [c[0] + r * Math.cos(end), c[1] + r * Math.sin(end)];
    arrowHead(tip, end + (ccw ? -Math.PI / 2 : Math.PI / 2), 9, style);
    ctx.fillStyle = style; ctx.font = "12px sans-serif";
    ctx.fillText(label, c[0] + r + 3, c[1] - r + 4);  // values: in the readout
  }
  function drawGround() {
    const a = X([0, 0]), b = X([g.l0, 0]);
    line(a, b, "#999", 2, [6, 4]);
    [a, b].forEach(function (p) {
      ctx.fillStyle = "#ccc"; ctx.strokeStyle = "#777"; ctx.lineWidth = 1;
      ctx.beginPath(); ctx.moveTo(p[0], p[1]); ctx.lineTo(p[0] - 12, p[1] + 18);
      ctx.lineTo(p[0] + 12, p[1] + 18); ctx.closePath(); ctx.fill(); ctx.stroke();
    });
  }
  function drawGhost(t) {
    if (!gh) return;
    const q = pose(gh, index(gh, t));
    if (!q) return;
    LINKS.forEach(function (L) {
      line(X(q[L[2]]), X(q[L[3]]), "rgba(120,120,120,0.45)", 5, [8, 5]);
    });
    JOINTS.forEach(function (k) {
      const p = X(q[k]); ctx.strokeStyle = "rgba(120,120,120,0.6)"; ctx.lineWidth = 1.5;
      ctx.beginPath(); ctx.arc(p[0], p[1], 6, 0, 2 * Math.PI); ctx.stroke();
    });
  }
  function drawPath(i) {  // the path of P, the part already travelled darker
    ctx.lineWidth = 1;
    for (let pass = 0; pass < 2; ++pass) {
      ctx.strokeStyle = pass === 0 ? "#e4e4e4" : "#888"; ctx.beginPath();
      const last = pass === 0 ? n - 1 : i;
      for (let j = 0, first = true; j <= last; ++j) {
        const q = pose(m, j);
        if (!q) { first = true; continue; }
        const p = X(q.P);
        if (first) ctx.moveTo(p[0], p[1]); else ctx.lineTo(p[0], p[1]);
        first = false;
      }
      ctx.stroke();
    }
  }
  function drawLoads(q, i) {
    const P = X(q.P);
    if (fMax > 0 && m.F[i] !== null && m.F[i] !== 0) {
      const a = q.th3 + g.F_angle, len = arrowLen * m.F[i] / fMax;
      const tip = X([q.P[0] + len * Math.cos(a), q.P[1] + len * Math.sin(a)]);
      line(P, tip, "#b00000", 3);
      arrowHead(tip, Math.atan2(tip[1] - P[1], tip[0] - P[0]), 12, "#b00000");
      ctx.fillStyle = "#b00000"; ctx.font = "12px sans-serif";
      ctx.fillText("F " + fmt(m.F[i], 3) + " N", tip[0] + 6, tip[1] - 6);
    }
    torqueArc(X(q.O), m.M1[i], mMax, "#1f77b4", "M1");
    if (m.M2) torqueArc(X(q.D0), m.M2[i], mMax, "#ff7f0e", "M2");
    const mid = X([(q.B[0] + q.C[0]) / 2, (q.B[1] + q.C[1]) / 2]);
    if (maxAbs(m.M3) > 0) torqueArc(mid, m.M3[i], m3Max, "#2ca02c", "M3");
  }
  function drawLinkage(q, i) {
    LINKS.forEach(function (L) { line(X(q[L[2]]), X(q[L[3]]), L[1], 7); });
    const P = X(q.P);
    ctx.fillStyle = "#000"; ctx.beginPath();
    ctx.moveTo(P[0], P[1] - 7); ctx.lineTo(P[0] + 7, P[1]); ctx.lineTo(P[0], P[1] + 7);
    ctx.lineTo(P[0] - 7, P[1]); ctx.closePath(); ctx.fill();
    ctx.font = "bold 13px sans-serif"; ctx.fillText("P", P[0] + 8, P[1] + 16);
    JOINTS.forEach(function (k, j) {
      const p = X(q[k]), power = m["p" + (j + 1)][i];
      ctx.fillStyle = colour(power / pMax); ctx.strokeStyle = "#000"; ctx.lineWidth = 1.5;
      ctx.beginPath(); ctx.arc(p[0], p[1], 9, 0, 2 * Math.PI); ctx.fill(); ctx.stroke();
      if (m.stuck[i] & (1 << j)) {
        ctx.strokeStyle = "#000"; ctx.lineWidth = 3; ctx.strokeRect(p[0] - 14, p[1] - 14, 28, 28);
      }
      ctx.fillStyle = "#000"; ctx.font = "bold 13px sans-serif";
      ctx.fillText(k, p[0] - 8, p[1] - 19);  // above the stuck square
    });
  }
  function drawLegend(i) {
    const x0 = W - PANEL + 10;
    ctx.fillStyle = "#f7f7f7"; ctx.fillRect(W - PANEL, 0, PANEL, H);
    ctx.fillStyle = "#000"; ctx.font = "bold 13px sans-serif";
    ctx.fillText("friction power |Mf w| [W]", x0, 20);
    ctx.font = "12px sans-serif"; ctx.fillText("colour ~ square root", x0, 36);
    for (let y = 0; y < 150; ++y) {  // the bar is linear in sqrt(power)
      ctx.fillStyle = colour(Math.pow(1 - y / 150, 2)); ctx.fillRect(x0, 46 + y, 18, 1);
    }
    ctx.font = "12px sans-serif"; ctx.fillStyle = "#000";
    if (pPeak === 0) {  // no scale to show: say so instead of inventing one
      ctx.fillText("0 at every", x0 + 24, 54); ctx.fillText("joint and t", x0 + 24, 70);
    } else {
      ctx.fillText((pPeak > pMax ? ">= " : "") + fmt(pMax, 3), x0 + 24, 54);
      if (pPeak > pMax) ctx.fillText("peak " + fmt(pPeak, 3), x0 + 24, 70);  // clear of the dots
      ctx.fillText(fmt(pMax / 4, 3), x0 + 24, 124);
    }
    ctx.fillText("0", x0 + 24, 196);
    JOINTS.forEach(function (k, j) {  // the current value of each joint
      const y = 58 + j * 30, x = x0 + 126, v = m["p" + (j + 1)][i];
      ctx.fillStyle = colour(v / pMax); ctx.strokeStyle = "#000"; ctx.lineWidth = 1;
      ctx.beginPath(); ctx.arc(x, y, 7, 0, 2 * Math.PI); ctx.fill(); ctx.stroke();
      ctx.fillStyle = "#000"; ctx.fillText(k + " " + fmt(v, 3), x + 14, y + 4);
      if (m.stuck[i] & (1 << j)) ctx.strokeRect(x - 10, y - 10, 20, 20);
    });
    let y = 224;
    const item = function (draw, text) {  // a sample drawn at height y, its text beside it
      draw(y);
      ctx.fillStyle = "#000"; ctx.font = "12px sans-serif"; ctx.fillText(text, x0 + 34, y + 4);
      y += 22;
    };
    LINKS.forEach(function (L) {
      item(function (yy) { line([x0, yy], [x0 + 26, yy], L[1], 6); }, L[0]);
    });
    item(function (yy) {
      ctx.strokeStyle = "#000"; ctx.lineWidth = 3; ctx.strokeRect(x0 + 6, yy - 8, 16, 16);
    }, "stuck joint (w = 0)");
    item(function (yy) {
      line([x0, yy], [x0 + 22, yy], "#b00000", 3); arrowHead([x0 + 28, yy], 0, 10, "#b00000");
    }, "F at P (length ~ |F|)");
    item(function (yy) { line([x0, yy], [x0 + 26, yy], "#888", 1); }, "path of P");
    item(function (yy) {
      ctx.strokeStyle = "#555"; ctx.lineWidth = 2;
      ctx.beginPath(); ctx.arc(x0 + 13, yy, 8, 0, 5); ctx.stroke();
    }, "torques, ccw positive");
    if (gh) {
      item(function (yy) {
        line([x0, yy], [x0 + 26, yy], "rgba(120,120,120,0.6)", 5, [8, 5]);
      }, DATA.ghost_label);
    }
  }
  function energies(i) {
    const dE = m.W_in[i] + m.W_ext[i] - m.E_diss[i];
    const p = POWERS.reduce(function (s, pk) { return s + (pk[i] || 0); }, 0);
    return "t = " + m.t[i].toFixed(4) + " s   (frame " + (i + 1) + " of " + n + ")\n" +
      "W_in " + fmt(m.W_in[i], 5) + " J   W_ext " + fmt(m.W_ext[i], 5) + " J   E_diss " +
      fmt(m.E_diss[i], 5) + " J   change of KE + PE " + fmt(dE, 5) + " J   P_diss " +
      fmt(p, 4) + " W\n" +
      "M1 " + fmt(m.M1[i], 4) + " N m   " + (m.M2 ? "M2 " + fmt(m.M2[i], 4) + " N m   " : "") +
      "M3 " + fmt(m.M3[i], 4) +
      " N m   F " + fmt(m.F[i], 4) + " N";
  }

  const slider = document.getElementById("slider"), button = document.getElementById("play");
  const speed = document.getElementById("speed"), readout = document.getElementById("readout");
  let t = m.t[0], playing = false, last = null;
  slider.max = String(n - 1);
  document.getElementById("title").textContent = DATA.title + ": " + DATA.label;
  document.getElementById("note").textContent = "Drawn to scale, y up. " + n + " frames of " +
    m.samples + " samples (" + (n < m.samples ? "decimated" : "all") + "); " +
    (pPeak === 0 ? "no joint dissipates friction power in this run (|Mf w| = 0 throughout). "
      : "joint colours by the square root of the friction power, from 0 to the 98th percentile " +
        "of the joints' friction powers over the run (" + fmt(pMax, 3) + " W; peak " +
        fmt(pPeak, 3) + " W). ") +
    "Add #t=0.5 to the address to open at t = 0.5 s.";

  function draw() {
    const i = index(m, t);
    ctx.clearRect(0, 0, W, H);
    ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, W, H);
    drawGround(); drawPath(i); drawGhost(t);
    const q = pose(m, i);
    if (q) { drawLinkage(q, i); drawLoads(q, i); }
    ctx.fillStyle = "#000"; ctx.font = "bold 15px sans-serif";
    ctx.fillText("t = " + m.t[i].toFixed(3) + " s", 12, 20);
    drawLegend(i);
    slider.value = String(i);
    readout.textContent = energies(i);
  }
  function tick(now) {
    if (playing) {
      if (last !== null) {
        t += (now - last) / 1000 * Number(speed.value);
        if (t > m.t[n - 1]) t = m.t[0];
      }
      last = now;
      draw();
      requestAnimationFrame(tick);
    }
  }
  function setPlaying(on) {
    playing = on; last = null; button.textContent = on ? "Pause" : "Play";
    if (on) requestAnimationFrame(tick);
  }
  function fromHash() {
    const match = /t=([-+0-9.eE]+)/.exec(location.hash);
    if (!match) return;
    t = Math.min(Math.max(Number(match[1]), m.t[0]), m.t[n - 1]);
    setPlaying(false);
  }
  button.addEventListener("click", function () { setPlaying(!playing); });
  slider.addEventListener("input", function () { t = m.t[Number(slider.value)]; draw(); });
  window.addEventListener("hashchange", function () { fromHash(); draw(); });
  fromHash();
  draw();
  if (document.body.dataset.status === "loading") document.body.dataset.status = "ok";
})();
</script>
</body>
</html>
)page";

}  // namespace fivebar::io
