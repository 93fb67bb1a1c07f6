// imu-fdi flight report: draws the embedded data as inline SVG, with a
// shared zoom/pan over time. No library, no network. Each plot is drawn as
// a min/max envelope per pixel column so no spike disappears at any zoom.
(function () {
  "use strict";
  var D = JSON.parse(document.getElementById("report-data").textContent);
  var NS = "http://www.w3.org/2000/svg";
  var W = 1000, LEFT = 70, RIGHT = 20, PH = 220, SH = 12, LANE_H = 16, TL_LEFT = 190;
  var full = [D.span_s[0], D.span_s[1]];
  if (!(full[1] > full[0])) full = [full[0], full[0] + 1];
  var view = full.slice();
  function esc(s) {
    return String(s).replace(/&/g, "&amp;").replace(/</g, "&lt;").replace(/>/g, "&gt;").replace(/"/g, "&quot;");
  }
  function ticks(lo, hi, n) {
    var span = hi - lo;
    if (!(span > 0) || !isFinite(span)) return [lo];
    var raw = span / n, mag = Math.pow(10, Math.floor(Math.log10(raw))), step = 10 * mag;
    [1, 2, 5, 10].some(function (m) { if (m * mag >= raw) { step = m * mag; return true; } return false; });
    var out = [];
    for (var i = Math.ceil(lo / step); i <= Math.floor(hi / step); i++) out.push(i * step);
    return out;
  }
  function fmt(v) { return String(+v.toFixed(6)); }
  function lowerBound(a, x) {
    var l = 0, h = a.length;
    while (l < h) { var m = (l + h) >> 1; if (a[m] < x) l = m + 1; else h = m; }
    return l;
  }
  // Min/max per pixel column of one series over the view: [x, lo, hi] or
  // null for a gap.
  function envelope(s, t0, t1, cols) {
    var t = D.times[s.time], lo = s.lo, hi = s.hi || s.lo;
    var w = (t1 - t0) / cols, out = [], cur = null, i = Math.max(0, lowerBound(t, t0) - 1);
    function flush() { if (cur) { out.push(cur); cur = null; } }
    for (; i < t.length; i++) {
      var ti = t[i];
      if (lo[i] === null) { flush(); out.push(null); if (ti > t1) break; continue; }
      var c = Math.floor((ti - t0) / w);
      if (c < -1) c = -1;
      if (c > cols) c = cols;
      if (cur && cur[0] === c) { cur[1] = Math.min(cur[1], lo[i]); cur[2] = Math.max(cur[2], hi[i]); }
      else { flush(); cur = [c, lo[i], hi[i]]; }
      if (ti > t1) break;
    }
    flush();
    return out;
  }
  function plotHeight(p) { return 28 + SH * p.strips.length + PH + 40; }
  function drawPlot(p, svg) {
    var top = 28 + SH * p.strips.length, w = W - LEFT - RIGHT, t0 = view[0], t1 = view[1];
    var x = function (t) { return LEFT + (t - t0) / (t1 - t0) * w; };
    var envs = p.series.map(function (s) { return envelope(s, t0, t1, Math.round(w)); });
    var y0 = Infinity, y1 = -Infinity, points = 0;
    envs.forEach(function (e) {
      e.forEach(function (b) {
        if (b && b[0] >= 0 && b[0] < w) { y0 = Math.min(y0, b[1]); y1 = Math.max(y1, b[2]); points++; }
      });
    });
    p.hlines.forEach(function (h) { y0 = Math.min(y0, h.y); y1 = Math.max(y1, h.y); });
    if (!(y1 >= y0)) { y0 = -1; y1 = 1; }
    var pad = Math.max((y1 - y0) * 0.05, 1e-9); y0 -= pad; y1 += pad;
    var y = function (v) { return top + (y1 - v) / (y1 - y0) * PH; };
    var h = [];
    h.push('<defs><clipPath id="c-' + p.id + '"><rect x="' + LEFT + '" y="0" width="' + w + '" height="' + (top + PH) + '"/></clipPath></defs>');
    h.push('<rect width="100%" height="100%" fill="white"/>');
    h.push('<text x="' + LEFT + '" y="16" font-size="13" font-weight="bold">' + esc(p.title) + '</text>');
    ticks(y0, y1, 5).forEach(function (v) {
      h.push('<line x1="' + LEFT + '" x2="' + (LEFT + w) + '" y1="' + y(v).toFixed(1) + '" y2="' + y(v).toFixed(1) + '" stroke="#eee"/>');
      h.push('<text x="' + (LEFT - 4) + '" y="' + (y(v) + 4).toFixed(1) + '" text-anchor="end">' + fmt(v) + '</text>');
    });
    ticks(t0, t1, 10).forEach(function (v) {
      h.push('<text x="' + x(v).toFixed(1) + '" y="' + (top + PH + 14) + '" text-anchor="middle">' + fmt(v) + '</text>');
    });
    h.push('<text x="' + (LEFT + w / 2) + '" y="' + (top + PH + 30) + '" text-anchor="middle">time (s)</text>');
    h.push('<text x="14" y="' + (top + PH / 2) + '" transform="rotate(-90 14 ' + (top + PH / 2) + ')" text-anchor="middle">' + esc(p.unit) + '</text>');
    h.push('<g clip-path="url(#c-' + p.id + ')">');
    p.strips.forEach(function (st, i) {
      var sy = 24 + SH * i;
      h.push('<rect x="' + LEFT + '" y="' + sy + '" width="' + w + '" height="' + (SH - 2) + '" fill="#f4f4f4"/>');
      st.intervals.forEach(function (iv) {
        if (iv.end_s < t0 || iv.start_s > t1) return;
        h.push('<rect x="' + x(iv.start_s).toFixed(1) + '" y="' + sy + '" width="' + Math.max(1, x(iv.end_s) - x(iv.start_s)).toFixed(1) +
          '" height="' + (SH - 2) + '" fill="' + iv.color + '"><title>' + esc(st.name + ": " + iv.label + " " + fmt(iv.start_s) + "–" + fmt(iv.end_s) + " s") + '</title></rect>');
      });
    });
    p.hlines.forEach(function (hl) {
      h.push('<line x1="' + LEFT + '" x2="' + (LEFT + w) + '" y1="' + y(hl.y).toFixed(1) + '" y2="' + y(hl.y).toFixed(1) + '" stroke="#000" stroke-dasharray="6 3"/>');
      h.push('<text x="' + (LEFT + w - 2) + '" y="' + (y(hl.y) - 3).toFixed(1) + '" text-anchor="end">' + esc(hl.label) + '</text>');
    });
    envs.forEach(function (e, k) {
      var s = p.series[k], d = "", pen = false;
      e.forEach(function (b) {
        if (!b) { pen = false; return; }
        var bx = (LEFT + b[0] + 0.5).toFixed(1);
        d += (pen ? "L" : "M") + bx + " " + y(b[2]).toFixed(1);
        if (b[1] !== b[2]) d += "L" + bx + " " + y(b[1]).toFixed(1);
        pen = true;
      });
      var dash = s.stroke === "dashed" ? ' stroke-dasharray="4 3" stroke-opacity="0.6"' : "";
      h.push('<path d="' + d + '" fill="none" stroke="' + s.color + '" stroke-width="1"' + dash + '><title>' + esc(s.name) + '</title></path>');
    });
    p.markers.forEach(function (m) {
      if (m.t_s < t0 || m.t_s > t1) return;
      h.push('<line x1="' + x(m.t_s).toFixed(1) + '" x2="' + x(m.t_s).toFixed(1) + '" y1="' + top + '" y2="' + (top + PH) + '" stroke="' + m.color + '" stroke-dasharray="2 2" stroke-width="1.5"><title>' + esc(m.label + " at " + fmt(m.t_s) + " s") + '</title></line>');
    });
    h.push('</g><rect x="' + LEFT + '" y="' + top + '" width="' + w + '" height="' + PH + '" fill="none" stroke="#888"/>');
    var lx = LEFT + 4;
    p.series.forEach(function (s) {
      if (s.stroke !== "solid") return;
      h.push('<rect x="' + lx + '" y="' + (top + 8) + '" width="10" height="3" fill="' + s.color + '"/><text x="' + (lx + 13) + '" y="' + (top + 12) + '">' + esc(s.name) + '</text>');
      lx += 20 + 6.5 * s.name.length;
    });
    p.strips.forEach(function (st, i) {
      h.push('<text x="' + (LEFT - 4) + '" y="' + (24 + SH * i + 9) + '" text-anchor="end" font-size="9">' + esc(st.name) + '</text>');
    });
    svg.innerHTML = h.join("");
    svg.setAttribute("data-points", String(points));
    return points;
  }
  function drawTimeline(tl, svg) {
    var w = W - TL_LEFT - RIGHT, t0 = view[0], t1 = view[1], h = [];
    var x = function (t) { return TL_LEFT + (t - t0) / (t1 - t0) * w; };
    h.push('<rect width="100%" height="100%" fill="white"/><text x="' + TL_LEFT + '" y="16" font-size="13" font-weight="bold">Health statuses over time</text>');
    h.push('<defs><clipPath id="c-timeline"><rect x="' + TL_LEFT + '" y="0" width="' + w + '" height="100%"/></clipPath></defs>');
    var drawn = 0;
    tl.lanes.forEach(function (lane, i) {
      var ly = 24 + LANE_H * i;
      h.push('<text x="' + (TL_LEFT - 4) + '" y="' + (ly + 11) + '" text-anchor="end">' + esc(lane.name) + '</text>');
      h.push('<g clip-path="url(#c-timeline)"><rect x="' + TL_LEFT + '" y="' + ly + '" width="' + w + '" height="' + (LANE_H - 3) + '" fill="#f4f4f4"/>');
      lane.intervals.forEach(function (iv) {
        if (iv.end_s < t0 || iv.start_s > t1) return;
        drawn++;
        h.push('<rect x="' + x(iv.start_s).toFixed(1) + '" y="' + ly + '" width="' + Math.max(1, x(iv.end_s) - x(iv.start_s)).toFixed(1) + '" height="' + (LANE_H - 3) +
          '" fill="' + iv.color + '"><title>' + esc(lane.name + ": " + iv.label + " " + fmt(iv.start_s) + "–" + fmt(iv.end_s) + " s") + '</title></rect>');
      });
      h.push('</g>');
    });
    var base = 24 + LANE_H * tl.lanes.length + 12;
    ticks(t0, t1, 10).forEach(function (v) {
      h.push('<text x="' + x(v).toFixed(1) + '" y="' + base + '" text-anchor="middle">' + fmt(v) + '</text>');
    });
    svg.innerHTML = h.join("");
    svg.setAttribute("data-points", String(drawn + tl.lanes.length));
  }
  var svgs = [], tlSvg = null, pending = false;
  function redraw() {
    pending = false;
    var empty = [];
    D.plots.forEach(function (p, i) { if (drawPlot(p, svgs[i]) === 0) empty.push(p.id); });
    if (tlSvg) drawTimeline(D.timeline, tlSvg);
    document.getElementById("view").textContent = fmt(view[0]) + " – " + fmt(view[1]) + " s";
    document.documentElement.setAttribute("data-empty-plots", empty.join(" "));
  }
  function schedule() { if (!pending) { pending = true; window.requestAnimationFrame(redraw); } }
  function setView(a, b) {
    var minSpan = Math.max((full[1] - full[0]) * 1e-5, 1e-3);
    if (b - a < minSpan) { var c = (a + b) / 2; a = c - minSpan / 2; b = c + minSpan / 2; }
    if (b - a > full[1] - full[0]) { a = full[0]; b = full[1]; }
    if (a < full[0]) { b += full[0] - a; a = full[0]; }
    if (b > full[1]) { a -= b - full[1]; b = full[1]; }
    view = [a, b];
    schedule();
  }
  function tAt(svg, clientX, left) {
    var r = svg.getBoundingClientRect(), px = (clientX - r.left) * W / r.width;
    return view[0] + (px - left) / (W - left - RIGHT) * (view[1] - view[0]);
  }
  function interact(svg, left) {
    svg.addEventListener("wheel", function (ev) {
      ev.preventDefault();
      var t = tAt(svg, ev.clientX, left), f = Math.exp(ev.deltaY * 0.002);
      setView(t - (t - view[0]) * f, t + (view[1] - t) * f);
    }, { passive: false });
    var drag = null;
    svg.addEventListener("pointerdown", function (ev) { drag = { x: ev.clientX, v: view.slice() }; svg.setPointerCapture(ev.pointerId); });
    svg.addEventListener("pointermove", function (ev) {
      if (!drag) return;
      var r = svg.getBoundingClientRect(), dt = -(ev.clientX - drag.x) * W / r.width / (W - left - RIGHT) * (drag.v[1] - drag.v[0]);
      setView(drag.v[0] + dt, drag.v[1] + dt);
    });
    svg.addEventListener("pointerup", function () { drag = null; });
    svg.addEventListener("dblclick", function () { setView(full[0], full[1]); });
  }
  var host = document.getElementById("plots");
  D.plots.forEach(function (p) {
    var hgt = plotHeight(p), svg = document.createElementNS(NS, "svg");
    svg.setAttribute("viewBox", "0 0 " + W + " " + hgt);
    svg.setAttribute("id", "plot-" + p.id);
    svg.setAttribute("class", "plot");
    host.appendChild(svg);
    interact(svg, LEFT);
    svgs.push(svg);
  });
  if (D.timeline.lanes.length) {
    tlSvg = document.createElementNS(NS, "svg");
    tlSvg.setAttribute("viewBox", "0 0 " + W + " " + (24 + LANE_H * D.timeline.lanes.length + 24));
    tlSvg.setAttribute("id", "plot-timeline");
    tlSvg.setAttribute("class", "plot");
    document.getElementById("timeline").appendChild(tlSvg);
    interact(tlSvg, TL_LEFT);
  }
  function zoom(f) { var c = (view[0] + view[1]) / 2, h = (view[1] - view[0]) * f / 2; setView(c - h, c + h); }
  document.getElementById("zoom-in").onclick = function () { zoom(0.5); };
  document.getElementById("zoom-out").onclick = function () { zoom(2); };
  document.getElementById("zoom-reset").onclick = function () { setView(full[0], full[1]); };
  redraw();
  document.documentElement.setAttribute("data-render", "done");
})();
