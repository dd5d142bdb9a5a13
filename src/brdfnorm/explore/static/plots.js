// brdfnorm explore: the page's plots (plotly.js's basic bundle, SVG only) — the lobe in the plane of N and V
// (normalized, and the raw f beside it; linear or in decades), the 3-D wireframe (drag to turn), the albedo curves.
// Loaded before app.js, whose `state` and `$` these functions use when called (never at load).
"use strict";

const CHANNEL_COLORS = ["#d62728", "#2ca02c", "#1f77b4"];
const PLOT_CONFIG = { displaylogo: false, responsive: true, modeBarButtonsToRemove: ["sendDataToCloud"] };
// -- plots --------------------------------------------------------------------------------------------------------
const BASE_LAYOUT = {
  margin: { l: 48, r: 16, t: 8, b: 40 }, font: { size: 11, family: "system-ui, sans-serif" },
  paper_bgcolor: "rgba(0,0,0,0)", plot_bgcolor: "#fbfbfd", showlegend: true,
  legend: { orientation: "h", y: -0.18, x: 0 },
};

// The lobe plot: the normalized α·f·(N·L) and, beside it, the raw f(L, V) (1/sr), each for the model and the
// overlay, in the plane of N and V. On the log scale the radius is the number of decades above PEAK/10^DECADES
// (0 at the centre, DECADES at the panel's peak), so a lobe a few degrees wide shows its shape and its tails.
const DECADES = 5;
const OVERLAY_COLOR = "#9467bd";

function radius(r, peak, log) {
  if (r === null) return null;
  if (!log) return r;
  return r > 0 ? Math.max(0, DECADES + Math.log10(r / peak)) : 0;
}

function lobePanel(traces, layout, n, curves, data, title) {
  const axis = n === 1 ? "" : String(n);
  const peak = Math.max(1e-300, ...curves.flatMap((c) => c.r.filter((v) => v !== null && Number.isFinite(v))));
  const log = state.logScale;
  const scale = log ? DECADES : peak;
  const t = data.lobe.t_deg.map((d) => d * Math.PI / 180);
  for (const c of curves) {
    const t_c = c.t_deg ? c.t_deg.map((d) => d * Math.PI / 180) : t;
    const rho = c.r.map((v) => radius(v, peak, log));
    traces.push({ x: rho.map((v, i) => (v === null ? null : v * Math.sin(t_c[i]))),
                  y: rho.map((v, i) => (v === null ? null : v * Math.cos(t_c[i]))), xaxis: "x" + axis,
                  yaxis: "y" + axis, type: "scatter", mode: "lines", name: c.name, meta: c.meta,
                  line: { color: c.color, width: 2, dash: c.dash || "solid" },
                  fill: c.dash ? "none" : "toself", fillcolor: "rgba(31,119,180,0.10)" });
  }
  const view = data.view_deg * Math.PI / 180;
  traces.push({ x: [0, scale * Math.sin(view)], y: [0, scale * Math.cos(view)], type: "scatter", xaxis: "x" + axis,
                yaxis: "y" + axis, mode: "lines+markers", name: "V (view)", showlegend: n === 1,
                line: { color: "#ff7f0e", width: 2 }, marker: { size: [0, 7] } });
  traces.push({ x: [0, -scale * Math.sin(view)], y: [0, scale * Math.cos(view)], type: "scatter",
                xaxis: "x" + axis, yaxis: "y" + axis, mode: "lines", name: "mirror of V", showlegend: n === 1,
                line: { color: "#888", dash: "dot", width: 1 } });
  if (log) {  // decade rings, labelled by their value relative to the peak
    for (let k = 1; k < DECADES; k++) {
      const arc = Array.from({ length: 61 }, (_, i) => -Math.PI / 2 + Math.PI * i / 60);
      traces.push({ x: arc.map((u) => k * Math.sin(u)), y: arc.map((u) => k * Math.cos(u)), xaxis: "x" + axis,
                    yaxis: "y" + axis, type: "scatter", mode: "lines", hoverinfo: "skip", showlegend: false,
                    line: { color: "#c9ced8", width: 1, dash: "dot" } });
    }
    const rings = Array.from({ length: DECADES }, (_, k) => k + 1);
    const names = rings.map((k) => (k === DECADES ? "peak" : `1e-${DECADES - k}`));
    traces.push({ x: rings.map(() => 0), y: rings, text: names,  // up the N axis: one text line per decade fits
                  xaxis: "x" + axis, yaxis: "y" + axis, type: "scatter", mode: "text", textposition: "middle left",
                  hoverinfo: "skip", showlegend: false, textfont: { size: 9, color: "#8a93a3" } });
  }
  const x = layout.raw ? [[0, 0.47], [0.53, 1]][n - 1] : [0, 1];
  layout["xaxis" + axis] = { domain: x, zeroline: true, range: [-1.1 * scale, 1.1 * scale], showticklabels: !log,
    title: { text: log ? `${title} (decades, peak ${peak.toPrecision(3)})` : title, font: { size: 10 } } };
  layout["yaxis" + axis] = { scaleanchor: "x" + axis, scaleratio: 1, range: [-0.05 * scale, 1.1 * scale],
    anchor: "x" + axis, title: n === 1 ? { text: "N" } : undefined, showticklabels: !log };
}

function plotLobe(data) {
  const main = state.modelLabel || "model";
  const second = data.overlay;
  const normalized = [{ r: data.lobe.r, name: `α·f·(N·L): ${main}`, color: "#1f77b4", meta: "normalized" }];
  const raw = [{ r: data.lobe.raw, name: `f: ${main}`, color: "#1f77b4", meta: "raw" }];
  if (second) {
    normalized.push({ r: second.lobe.r, t_deg: second.lobe.t_deg, name: `α·f·(N·L): ${second.label}`,
                      color: OVERLAY_COLOR, dash: "dash", meta: "overlay normalized" });
    raw.push({ r: second.lobe.raw, t_deg: second.lobe.t_deg, name: `f: ${second.label}`, color: OVERLAY_COLOR,
               dash: "dash", meta: "overlay raw" });
  }
  const traces = [];
  const layout = { ...BASE_LAYOUT, raw: state.rawF };
  lobePanel(traces, layout, 1, normalized, data, "normalized α·f·(N·L)");
  if (state.rawF) lobePanel(traces, layout, 2, raw, data, "raw f (1/sr)");
  delete layout.raw;
  layout.legend = { orientation: "h", y: -0.22, x: 0 };
  layout.margin = { l: 40, r: 8, t: 8, b: 48 };
  Plotly.react("plot-lobe", traces, layout, PLOT_CONFIG);
}

// The 3-D lobe is drawn as a wireframe projected in this script (drag to turn it): SVG, like the other plots,
// because a WebGL scene costs seconds to start and a third of a second per frame where WebGL runs in software.
const camera = { azimuth: -55, elevation: 22 };
const RING_COLORS = ["#440154", "#3b528b", "#21918c", "#5ec962", "#fde725"];

function project(x, y, z) {
  const a = camera.azimuth * Math.PI / 180;
  const e = camera.elevation * Math.PI / 180;
  const across = x * Math.cos(a) + y * Math.sin(a);
  const depth = -x * Math.sin(a) + y * Math.cos(a);
  return [across, z * Math.cos(e) + depth * Math.sin(e)];
}

function polyline(points) {  // [[x, y, z], ...] -> projected xs, ys with a null after the line
  const xs = [], ys = [];
  for (const [x, y, z] of points) {
    if (x === null || y === null || z === null) { xs.push(null); ys.push(null); continue; }
    const [u, v] = project(x, y, z);
    xs.push(u); ys.push(v);
  }
  xs.push(null); ys.push(null);
  return [xs, ys];
}

function plotSurface(data) {
  const s = data.surface;
  state.lastSurface = s;
  const rows = s.x.length, columns = s.x[0].length;
  let radius = 1e-300;
  for (let i = 0; i < rows; i++) for (let j = 0; j < columns; j++) {
    if (s.x[i][j] !== null) radius = Math.max(radius, Math.hypot(s.x[i][j], s.y[i][j], s.z[i][j]));
  }
  const traces = [];
  const line = (points, color, width, name, dash) => {
    const [x, y] = polyline(points);
    traces.push({ x, y, type: "scatter", mode: "lines", hoverinfo: "skip", name,
                  line: { color, width, dash: dash || "solid" } });
  };
  const circle = [];
  for (let k = 0; k <= 72; k++) {
    const t = 2 * Math.PI * k / 72;
    circle.push([radius * Math.cos(t), radius * Math.sin(t), 0]);
  }
  line(circle, "#b8bec9", 1, "horizon", "dot");
  line([[-radius, 0, 0], [radius, 0, 0]], "#b8bec9", 1, "X axis");
  line([[0, -radius, 0], [0, radius, 0]], "#b8bec9", 1, "Y axis");
  line([[0, 0, 0], [0, 0, radius]], "#8a93a3", 1.5, "N");
  const meridians = [];  // lines of constant azimuth about the mirror direction
  for (let j = 0; j < columns; j += 2) {
    meridians.push(...Array.from({ length: rows }, (_, i) => [s.x[i][j], s.y[i][j], s.z[i][j]]), [null, null, null]);
  }
  line(meridians, "rgba(59,82,139,0.45)", 1, "lobe");
  const bands = RING_COLORS.map(() => []);  // rings about the mirror direction, coloured from the peak outwards
  for (let i = 1; i < rows; i++) {
    const band = bands[Math.min(bands.length - 1, Math.floor(bands.length * i / rows))];
    band.push(...Array.from({ length: columns }, (_, j) => [s.x[i][j], s.y[i][j], s.z[i][j]]), [null, null, null]);
  }
  bands.forEach((points, k) => line(points, RING_COLORS[k], 1.2, "lobe"));
  line([[0, 0, 0], s.view.map((c) => c * radius)], "#ff7f0e", 3, "V (view)");
  const labels = [["N", [0, 0, 1.08 * radius]], ["X", [1.1 * radius, 0, 0]], ["Y", [0, 1.1 * radius, 0]],
                  ["V", s.view.map((c) => 1.1 * c * radius)]];
  const placed = labels.map(([, p]) => project(...p));
  traces.push({ x: placed.map((p) => p[0]), y: placed.map((p) => p[1]), text: labels.map(([t]) => t),
                type: "scatter", mode: "text", hoverinfo: "skip", textfont: { size: 12, color: "#5d6677" } });
  const layout = { ...BASE_LAYOUT, margin: { l: 8, r: 8, t: 8, b: 8 }, showlegend: false, dragmode: false,
    plot_bgcolor: "rgba(0,0,0,0)",
    xaxis: { visible: false, range: [-1.2 * radius, 1.2 * radius], fixedrange: true },
    yaxis: { visible: false, scaleanchor: "x", scaleratio: 1, fixedrange: true },
    annotations: [{ text: "drag to turn", xref: "paper", yref: "paper", x: 1, y: 0, showarrow: false,
                    font: { size: 10, color: "#8a93a3" }, xanchor: "right", yanchor: "bottom" }] };
  Plotly.react("plot-3d", traces, layout, { ...PLOT_CONFIG, staticPlot: false, displayModeBar: false });
}

function enableTurning() {
  const div = $("plot-3d");
  let last = null;
  let queued = false;
  div.addEventListener("pointerdown", (event) => { last = [event.clientX, event.clientY]; div.setPointerCapture(event.pointerId); });
  div.addEventListener("pointerup", () => { last = null; });
  div.addEventListener("pointermove", (event) => {
    if (!last || !state.lastSurface) return;
    camera.azimuth -= 0.4 * (event.clientX - last[0]);
    camera.elevation = Math.min(89, Math.max(-10, camera.elevation + 0.4 * (event.clientY - last[1])));
    last = [event.clientX, event.clientY];
    if (!queued) {
      queued = true;
      requestAnimationFrame(() => { queued = false; plotSurface({ surface: state.lastSurface }); });
    }
  });
}

function plotAlbedo(data) {
  const c = data.curve;
  const traces = [];
  const names = c.value.length === 1 ? [""] : [" R", " G", " B"];
  c.value.forEach((values, k) => {
    const error = c.error[Math.min(k, c.error.length - 1)];
    const upper = values.map((v, i) => (v === null ? null : v + error[i]));
    const lower = values.map((v, i) => (v === null ? null : v - error[i]));
    const color = c.value.length === 1 ? "#1f77b4" : CHANNEL_COLORS[k];
    traces.push({ x: c.theta_deg, y: lower, type: "scatter", mode: "lines", line: { width: 0 },
                  showlegend: false, hoverinfo: "skip" });
    traces.push({ x: c.theta_deg, y: upper, type: "scatter", mode: "lines", line: { width: 0 }, fill: "tonexty",
                  fillcolor: "rgba(31,119,180,0.25)", name: "error band" + names[k], hoverinfo: "skip",
                  showlegend: k === 0 });
    traces.push({ x: c.theta_deg, y: values, type: "scatter", mode: "lines", name: "E(θ_o)" + names[k],
                  line: { color, width: 2 }, customdata: error,
                  hovertemplate: "θ_o %{x:.1f}°: E = %{y:.10g} ± %{customdata:.1e}<extra></extra>" });
  });
  c.normalized.forEach((values, k) => {
    traces.push({ x: c.theta_deg, y: values, type: "scatter", mode: "lines", yaxis: "y2",
                  name: `α·E (${data.convention})` + (c.normalized.length === 1 ? "" : names[k]),
                  line: { color: c.normalized.length === 1 ? "#2ca02c" : CHANNEL_COLORS[k], dash: "dash", width: 2 } });
  });
  const second = data.overlay;
  if (second) {  // the overlay's largest channel, dashed, in both panels
    const largest = (columns) => columns[0].map((_, i) => Math.max(...columns.map((col) => col[i] ?? -Infinity)));
    traces.push({ x: second.curve.theta_deg, y: largest(second.curve.value), type: "scatter", mode: "lines",
                  name: `E(θ_o): ${second.label}`, line: { color: OVERLAY_COLOR, width: 2, dash: "dash" } });
    traces.push({ x: second.curve.theta_deg, y: largest(second.curve.normalized), type: "scatter", mode: "lines",
                  yaxis: "y2", name: `α·E: ${second.label}`, line: { color: OVERLAY_COLOR, width: 2, dash: "dot" } });
  }
  // Two panels sharing θ_o: E with its band above, α·E (the energy kept, 1 = all of it) below.
  const scale = state.logScale ? { type: "log", autorange: true } : { type: "linear", rangemode: "tozero" };
  const layout = { ...BASE_LAYOUT, margin: { l: 64, r: 16, t: 8, b: 64 },
    xaxis: { title: { text: "θ_o (degrees)", standoff: 4 }, range: [0, 90], anchor: "y2" },
    yaxis: { title: { text: "E(θ_o)" }, domain: [0.45, 1], ...scale },
    yaxis2: { title: { text: "α·E" }, domain: [0, 0.36], ...scale },
    shapes: [
      { type: "line", xref: "x", yref: "paper", x0: data.view_deg, x1: data.view_deg, y0: 0, y1: 1,
        line: { color: "#ff7f0e", width: 1, dash: "dot" } },
      { type: "line", xref: "paper", yref: "y2", x0: 0, x1: 1, y0: 1, y1: 1, line: { color: "#999", width: 1 } },
    ],
    legend: { orientation: "h", x: 0, y: -0.16, traceorder: "normal" } };
  Plotly.react("plot-albedo", traces, layout, PLOT_CONFIG);
}
