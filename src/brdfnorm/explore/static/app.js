// brdfnorm explore: the page's loop. Controls -> POST /api/evaluate (coarse, then fine) -> plots and readouts.
// Everything from the server is inserted as text (textContent, option labels), never as HTML.
"use strict";

const $ = (id) => document.getElementById(id);
const state = {
  modelId: null,
  description: null,
  values: {},
  view: 30,
  convention: "normal",
  client: Math.random().toString(36).slice(2) + Date.now().toString(36),
  generation: 0,
  inflight: false,
  pending: false,
  fitGeneration: 0,
  fileError: null,
  requestError: null,
  fitCode: "",
  movedAt: new Map(),  // generation -> performance.now() of the control move (for the latency readout)
};
// plotly.js is deferred after this script: requests start while it is parsed, drawing waits for it.
const plotlyReady = new Promise((resolve) => window.addEventListener("DOMContentLoaded", resolve));
const nextFrame = () => new Promise((resolve) => requestAnimationFrame(() => setTimeout(resolve, 0)));
const CHANNEL_COLORS = ["#d62728", "#2ca02c", "#1f77b4"];
const PLOT_CONFIG = { displaylogo: false, responsive: true, modeBarButtonsToRemove: ["sendDataToCloud"] };

async function getJSON(url) {
  const response = await fetch(url, { cache: "no-store" });
  const data = await response.json();
  if (!response.ok) throw new Error(data.error || response.statusText);
  return data;
}

async function postJSON(url, body) {
  const response = await fetch(url, {
    method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body),
  });
  const data = await response.json();
  return { status: response.status, data };
}

// -- errors and status ----------------------------------------------------------------------------------------
function showErrors() {
  const box = $("error");
  const lines = [state.fileError, state.requestError].filter(Boolean);
  box.textContent = lines.join("\n");
  box.hidden = lines.length === 0;
}

function setStatus(text, kind) {
  const status = $("status");
  status.textContent = text;
  status.className = "status " + (kind || "");
  document.body.dataset.state = kind || "idle";
}

// -- controls ---------------------------------------------------------------------------------------------------
function sliderToValue(slider, position) {
  return slider.log ? slider.low * Math.pow(slider.high / slider.low, position / 1000) : position;
}

function valueToSlider(slider, value) {
  if (!slider.log) return value;
  const clamped = Math.min(Math.max(value, slider.low), slider.high);
  return 1000 * Math.log(clamped / slider.low) / Math.log(slider.high / slider.low);
}

function formatNumber(value) {
  return Number.isInteger(value) ? String(value) : String(Number(value.toPrecision(6)));
}

function hexToRGB(hex) {
  return [1, 3, 5].map((i) => parseInt(hex.slice(i, i + 2), 16) / 255);
}

function rgbToHex(rgb) {
  return "#" + rgb.map((c) => Math.round(Math.min(Math.max(c, 0), 1) * 255).toString(16).padStart(2, "0")).join("");
}

function element(tag, attributes, text) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attributes || {})) node.setAttribute(key, value);
  if (text !== undefined) node.textContent = text;
  return node;
}

function buildControls(description, previous) {
  const container = $("params");
  container.replaceChildren();
  const values = {};
  for (const p of description.parameters) {
    const kept = previous && Object.prototype.hasOwnProperty.call(previous, p.name)
      && typeof previous[p.name] === typeof p.default && (p.kind !== "choice" || p.choices.includes(previous[p.name]));
    values[p.name] = kept ? previous[p.name] : p.default;
    const row = element("div", { class: "control" });
    const label = element("label", { for: "param-" + p.name, title: p.description || "" }, p.name);
    row.append(label);
    if (p.kind === "float") {
      const s = p.slider;
      const range = element("input", {
        type: "range", id: "param-" + p.name, "data-testid": "param-" + p.name,
        min: s.log ? 0 : s.low, max: s.log ? 1000 : s.high, step: "any",
      });
      range.value = valueToSlider(s, values[p.name]);
      const box = element("input", { type: "number", step: "any", "data-testid": "param-" + p.name + "-value",
        "aria-label": p.name });
      box.value = formatNumber(values[p.name]);
      range.addEventListener("input", () => {
        const value = sliderToValue(s, Number(range.value));
        state.values[p.name] = s.log ? Number(value.toPrecision(6)) : value;
        box.value = formatNumber(state.values[p.name]);
        schedule();
      });
      box.addEventListener("change", () => {
        const value = Number(box.value);
        if (box.value.trim() === "" || !Number.isFinite(value)) { box.value = formatNumber(state.values[p.name]); return; }
        state.values[p.name] = value;
        range.value = valueToSlider(s, value);
        schedule();
      });
      row.append(range, box);
      const hint = p.strict ? "" : " (slider range)";
      row.append(element("small", { class: "range" },
        `[${p.minimum ?? "−∞"}, ${p.maximum ?? "∞"}]${hint}${s.log ? ", log slider" : ""}`));
    } else if (p.kind === "bool") {
      const box = element("input", { type: "checkbox", role: "switch", id: "param-" + p.name,
        "data-testid": "param-" + p.name });
      box.checked = values[p.name];
      box.addEventListener("change", () => { state.values[p.name] = box.checked; schedule(); });
      row.append(box);
    } else if (p.kind === "color") {
      const picker = element("input", { type: "color", id: "param-" + p.name, "data-testid": "param-" + p.name });
      picker.value = rgbToHex(values[p.name]);
      const shown = element("small", { class: "range" }, values[p.name].map(formatNumber).join(", "));
      picker.addEventListener("input", () => {
        state.values[p.name] = hexToRGB(picker.value);
        shown.textContent = state.values[p.name].map(formatNumber).join(", ");
        schedule();
      });
      row.append(picker, shown);
    } else {
      const menu = element("select", { id: "param-" + p.name, "data-testid": "param-" + p.name });
      for (const choice of p.choices || []) menu.append(element("option", { value: choice }, choice));
      menu.value = values[p.name];
      menu.addEventListener("change", () => { state.values[p.name] = menu.value; schedule(); });
      row.append(menu);
    }
    container.append(row);
  }
  state.values = values;
  buildFitControls(description);
}

function buildFitControls(description) {
  const menu = $("fit-parameter");
  const before = menu.value;
  menu.replaceChildren();
  const floats = description.parameters.filter((p) => p.kind === "float");
  for (const p of floats) menu.append(element("option", { value: p.name }, p.name));
  if (floats.some((p) => p.name === before)) menu.value = before;
  $("fit-run").disabled = floats.length === 0;
  setFitRange();
}

function setFitRange() {
  const p = (state.description?.parameters || []).find((q) => q.name === $("fit-parameter").value);
  if (!p) return;
  $("fit-low").value = formatNumber(p.slider.low);
  $("fit-high").value = formatNumber(p.slider.high);
  $("fit-scale").value = p.slider.log ? "log" : "linear";
}

// -- the update loop ---------------------------------------------------------------------------------------------
function request(quality, generation) {
  return { model: state.modelId, params: state.values, view: state.view, convention: state.convention,
           quality, client: state.client, generation };
}

// A control moved: a new generation. One coarse request at a time; moves during it coalesce into one more.
function schedule() {
  state.generation += 1;
  state.movedAt.set(state.generation, performance.now());
  if (state.movedAt.size > 64) state.movedAt.delete(state.movedAt.keys().next().value);
  document.body.dataset.generation = String(state.generation);
  if (state.inflight) { state.pending = true; return; }
  run();
}

// The first view's three requests start together, before plotly.js is compiled: while it compiles the main thread
// is busy, so a request chained after another's answer would wait for it. The server names the first model
// (data-first-model) unless the address does; the first coarse view is asked for at the declared defaults.
const firstView = (() => {
  const model = new URLSearchParams(location.search).get("model") || document.body.dataset.firstModel;
  const body = { model, params: null, view: state.view, convention: state.convention, quality: "coarse",
                 client: state.client, generation: 1 };
  return { model, body, catalog: getJSON("/api/models"),
           description: getJSON("/api/models/" + encodeURIComponent(model)).catch(() => null),
           view: postJSON("/api/evaluate", body).catch((error) => ({ status: 0, data: { error: error.message } })) };
})();

function prefetched(body) {  // the first view's answer, if this is the request it answered
  const first = firstView.body;
  const same = ["model", "view", "convention", "quality", "generation"].every((key) => body[key] === first[key]);
  return same ? firstView.view : null;  // (generation 1 is the first model's first view, at its defaults)
}

async function run() {
  state.inflight = true;
  state.pending = false;
  const generation = state.generation;
  setStatus("computing…", "busy");
  let coarse;
  try {
    const body = request("coarse", generation);
    coarse = await (prefetched(body) || postJSON("/api/evaluate", body));
  } catch (error) {
    coarse = { status: 0, data: { error: "the server is not answering (" + error.message + ")" } };
  }
  state.inflight = false;
  if (state.pending) { run(); return; }
  if (!(await accept(coarse, generation))) return;  // (accept returns once the coarse plots are on screen)
  setStatus("refining…", "refining");
  let fine;
  try {
    fine = await postJSON("/api/evaluate", request("fine", generation));
  } catch (error) {
    fine = { status: 0, data: { error: "the server is not answering (" + error.message + ")" } };
  }
  if (await accept(fine, generation)) setStatus("refined: exact to the errors shown", "idle");
}

async function accept(response, generation) {
  if (response.status === 409 || generation !== state.generation) return false;
  if (response.status !== 200) {
    state.requestError = response.data.error || "request failed";
    showErrors();
    setStatus("error", "failed");
    return false;
  }
  state.requestError = null;
  showErrors();
  await render(response.data, generation);
  return generation === state.generation;
}

async function render(data, generation) {
  const readouts = data.readouts;
  const targets = { albedo: "readout-albedo", factor_normal: "readout-factor-normal",
                    factor_max: "readout-factor-max", factor_view: "readout-factor-view", energy: "readout-energy" };
  for (const [key, id] of Object.entries(targets)) {
    const node = $(id);
    node.textContent = readouts[key].text;
    node.dataset.quality = data.quality;
    node.dataset.generation = String(generation);
    if (readouts[key].value) node.dataset.value = JSON.stringify(readouts[key].value);
    else delete node.dataset.value;  // (the coarse pass's pending energy verdict has no number of its own)
  }
  const energy = $("readout-energy");
  energy.dataset.status = readouts.energy.status || "pending";  // pass, fail, inconclusive: brdfnorm check's
  energy.title = readouts.energy.message || "";
  $("readout-energy-command").textContent = readouts.energy.command ? "same as: " + readouts.energy.command : "";
  $("argmax").textContent = `(θ_o = ${readouts.factor_max.theta_deg.toFixed(2)}°)`;
  $("quality").textContent = data.quality === "fine" ? "refined" : "coarse, refining…";
  const warnings = $("warnings");
  warnings.replaceChildren(...data.warnings.map((w) => element("li", {}, w)));
  const numbers = performance.now();
  await plotlyReady;  // the numbers need no plotting library; on a first visit they come before it is ready
  if (generation !== state.generation) return;
  const timings = {};
  const draw = (name, plot) => {
    const begin = performance.now();
    plot(data);
    timings[name] = Math.round(performance.now() - begin);
  };
  draw("lobe", plotLobe);
  draw("albedo", plotAlbedo);
  const flat = performance.now();
  draw("surface", plotSurface);
  await nextFrame();  // on screen
  // Where the time of the last update went (the status tooltip shows it; the benchmark reads it).
  const moved = state.movedAt.get(generation);
  const now = performance.now();
  const timing = { ...data.timing, draw_ms: timings, generation, page_ms: Math.round(now),
                   check_ms: readouts.energy.elapsed_ms ?? null,
                   page_numbers_ms: Math.round(numbers),
                   page_2d_ms: Math.round(flat), latency_ms: moved === undefined ? null : Math.round(now - moved),
                   latency_2d_ms: moved === undefined ? null : Math.round(flat - moved) };
  document.body.dataset[data.quality + "Timing"] = JSON.stringify(timing);
  $("status").title = `${data.quality}: server ${Math.round(timing.compute_ms)} ms, `
    + `move to plots ${timing.latency_ms} ms`;
}

// -- plots --------------------------------------------------------------------------------------------------------
const BASE_LAYOUT = {
  margin: { l: 48, r: 16, t: 8, b: 40 }, font: { size: 11, family: "system-ui, sans-serif" },
  paper_bgcolor: "rgba(0,0,0,0)", plot_bgcolor: "#fbfbfd", showlegend: true,
  legend: { orientation: "h", y: -0.18, x: 0 },
};

function plotLobe(data) {
  const t = data.lobe.t_deg.map((d) => d * Math.PI / 180);
  const r = data.lobe.r;
  const x = r.map((v, i) => (v === null ? null : v * Math.sin(t[i])));
  const y = r.map((v, i) => (v === null ? null : v * Math.cos(t[i])));
  const scale = Math.max(1e-300, ...r.filter((v) => v !== null));
  const view = data.view_deg * Math.PI / 180;
  const traces = [
    { x, y, type: "scatter", mode: "lines", name: "α·f·(N·L)", line: { color: "#1f77b4", width: 2 },
      fill: "toself", fillcolor: "rgba(31,119,180,0.12)" },
    { x: [0, scale * Math.sin(view)], y: [0, scale * Math.cos(view)], type: "scatter", mode: "lines+markers",
      name: "V (view)", line: { color: "#ff7f0e", width: 2 }, marker: { size: [0, 7] } },
    { x: [0, -scale * Math.sin(view)], y: [0, scale * Math.cos(view)], type: "scatter", mode: "lines",
      name: "mirror of V", line: { color: "#888", dash: "dot", width: 1 } },
  ];
  const layout = { ...BASE_LAYOUT,
    xaxis: { title: { text: "X" }, zeroline: true, range: [-1.1 * scale, 1.1 * scale] },
    yaxis: { title: { text: "N" }, scaleanchor: "x", scaleratio: 1, range: [-0.05 * scale, 1.1 * scale] } };
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
  // Two panels sharing θ_o: E with its band above, α·E (the energy kept, 1 = all of it) below.
  const layout = { ...BASE_LAYOUT, margin: { l: 64, r: 16, t: 8, b: 64 },
    xaxis: { title: { text: "θ_o (degrees)", standoff: 4 }, range: [0, 90], anchor: "y2" },
    yaxis: { title: { text: "E(θ_o)" }, rangemode: "tozero", domain: [0.45, 1] },
    yaxis2: { title: { text: "α·E" }, rangemode: "tozero", domain: [0, 0.36] },
    shapes: [
      { type: "line", xref: "x", yref: "paper", x0: data.view_deg, x1: data.view_deg, y0: 0, y1: 1,
        line: { color: "#ff7f0e", width: 1, dash: "dot" } },
      { type: "line", xref: "paper", yref: "y2", x0: 0, x1: 1, y0: 1, y1: 1, line: { color: "#999", width: 1 } },
    ],
    legend: { orientation: "h", x: 0, y: -0.16, traceorder: "normal" } };
  Plotly.react("plot-albedo", traces, layout, PLOT_CONFIG);
}

// -- models and live files ---------------------------------------------------------------------------------------
async function selectModel(id, keepValues) {
  const first = id === firstView.model && !keepValues && state.modelId === null ? await firstView.description : null;
  const description = first || await getJSON("/api/models/" + encodeURIComponent(id));
  const previous = keepValues ? state.values : null;
  state.modelId = id;
  state.description = description;
  $("formula").textContent = description.formula;
  buildControls(description, previous);
  state.fileError = description.error ? description.error.text : null;
  showErrors();
  schedule();
}

function listen() {
  const events = new EventSource("/api/events");
  events.onmessage = (event) => {
    const message = JSON.parse(event.data);
    if (message.model !== state.modelId) return;
    if (message.error) {  // keep the last good plots and numbers; say where the file is wrong
      state.fileError = message.error.text;
      showErrors();
      setStatus("file has an error", "failed");
    } else {
      selectModel(state.modelId, true).catch((error) => { state.requestError = error.message; showErrors(); });
    }
  };
}

// -- fit panel ------------------------------------------------------------------------------------------------------
async function runFit() {
  state.fitGeneration += 1;
  const generation = state.fitGeneration;
  $("fit-summary").textContent = "fitting… (a sweep of exact factors, then the fit)";
  $("fit-copy").disabled = true;
  const body = { model: state.modelId, params: state.values, parameter: $("fit-parameter").value,
                 low: Number($("fit-low").value), high: Number($("fit-high").value),
                 samples: Math.round(Number($("fit-samples").value)), scale: $("fit-scale").value,
                 at: $("fit-at").value, language: $("fit-language").value, client: state.client, generation };
  const { status, data } = await postJSON("/api/fit", body);
  if (status === 409 || generation !== state.fitGeneration) return;
  if (status !== 200) {
    $("fit-summary").textContent = "fit failed: " + data.error;
    $("fit-code").textContent = "";
    return;
  }
  state.fitCode = data.code;
  $("fit-code").textContent = data.code;
  $("fit-copy").disabled = false;
  const [low, high] = data.range;
  $("fit-summary").textContent = `α at ${data.at} over ${data.parameter} ∈ [${formatNumber(low)}, ${formatNumber(high)}]`
    + ` (${data.samples} samples): ${data.form}, max relative error ${data.max_rel_error.toExponential(2)}`
    + (data.warnings.length ? " — " + data.warnings.join("; ") : "");
}

async function copyCode() {
  try {
    await navigator.clipboard.writeText(state.fitCode);
  } catch {
    const range = document.createRange();
    range.selectNodeContents($("fit-code"));
    const selection = window.getSelection();
    selection.removeAllRanges();
    selection.addRange(range);
    document.execCommand("copy");
  }
  $("fit-copy").textContent = "Copied";
  setTimeout(() => { $("fit-copy").textContent = "Copy code"; }, 1200);
}

// -- start ----------------------------------------------------------------------------------------------------------
async function start() {
  const catalog = await firstView.catalog;
  const picker = $("model");
  const groups = {};
  for (const entry of catalog.models) {
    if (!groups[entry.group]) {
      groups[entry.group] = element("optgroup", { label: entry.group });
      picker.append(groups[entry.group]);
    }
    groups[entry.group].append(element("option", { value: entry.id }, entry.label + (entry.watched ? " (watched)" : "")));
  }
  const first = new URLSearchParams(location.search).get("model");
  picker.value = catalog.models.some((m) => m.id === first) ? first : catalog.models[0].id;
  picker.addEventListener("change", () => selectModel(picker.value, false));
  $("convention").addEventListener("change", () => { state.convention = $("convention").value; schedule(); });
  const slider = $("view-angle");
  const box = $("view-angle-value");
  slider.addEventListener("input", () => { state.view = Number(slider.value); box.value = slider.value; schedule(); });
  box.addEventListener("change", () => {
    const value = Number(box.value);
    if (!(value >= 0 && value <= catalog.view_max_deg)) { box.value = String(state.view); return; }
    state.view = value;
    slider.value = String(value);
    schedule();
  });
  $("fit-parameter").addEventListener("change", setFitRange);
  enableTurning();
  $("fit-run").addEventListener("click", runFit);
  $("fit-copy").addEventListener("click", copyCode);
  listen();
  await selectModel(picker.value, false);
}

start().catch((error) => { state.requestError = "cannot start: " + error.message; showErrors(); });
