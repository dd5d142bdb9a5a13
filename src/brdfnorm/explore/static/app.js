// brdfnorm explore: the page's loop. Controls -> POST /api/evaluate (coarse, then fine) -> plots (plots.js) and
// readouts.
// Everything from the server is inserted as text (textContent, option labels), never as HTML.
"use strict";

const $ = (id) => document.getElementById(id);
const state = {
  modelId: null,
  description: null,
  values: {},
  view: 30,
  phi: 0,
  convention: "normal",
  logScale: false,  // lobe radius in decades below its peak, E on a log axis
  rawF: true,  // the raw f(L, V) beside the normalized lobe
  overlay: { on: false, modelId: null, description: null, values: {}, label: "" },
  lastData: null,
  overlayOn: false,
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

// One row per declared parameter, drawn as the server's `control` says (catalog.py's control_of): a slider with a
// number box, numbers per channel (η, k, f0: any value in range, not 8-bit colour steps), a colour picker, a
// switch labelled with its name and state, a menu. `values` is filled and changed in place; `prefix` names the
// inputs (param-, overlay-param-).
function buildControls(description, previous, container, values, prefix) {
  container.replaceChildren();
  for (const key of Object.keys(values)) delete values[key];
  for (const p of description.parameters) {
    const control = p.control || { float: "slider", bool: "switch", color: "colour" }[p.kind] || "menu";
    const kept = previous && Object.prototype.hasOwnProperty.call(previous, p.name)
      && Array.isArray(previous[p.name]) === Array.isArray(p.default)
      && typeof previous[p.name] === typeof p.default && (control !== "menu" || p.choices.includes(previous[p.name]));
    values[p.name] = kept ? previous[p.name] : p.default;
    const id = prefix + p.name;
    const row = element("div", { class: "control" });
    if (control !== "switch") row.append(element("label", { for: id, title: p.description || "" }, p.name));
    const range = `[${p.minimum ?? "−∞"}, ${p.maximum ?? "∞"}]${p.strict ? "" : " (slider range)"}`;
    if (control === "slider") {
      const s = p.slider;
      const slider = element("input", {
        type: "range", id, "data-testid": id, min: s.log ? 0 : s.low, max: s.log ? 1000 : s.high,
        step: s.log ? "any" : (s.step ?? "any"),
      });
      slider.value = valueToSlider(s, values[p.name]);
      const box = element("input", { type: "number", step: s.step ?? "any", "data-testid": id + "-value",
        "aria-label": p.name });
      box.value = formatNumber(values[p.name]);
      slider.addEventListener("input", () => {
        const value = sliderToValue(s, Number(slider.value));
        values[p.name] = s.log ? Number(value.toPrecision(6)) : value;
        box.value = formatNumber(values[p.name]);
        schedule();
      });
      box.addEventListener("change", () => {
        const value = Number(box.value);
        if (box.value.trim() === "" || !Number.isFinite(value)) { box.value = formatNumber(values[p.name]); return; }
        values[p.name] = value;
        slider.value = valueToSlider(s, value);
        schedule();
      });
      row.append(slider, box, element("small", { class: "range" }, range + (s.log ? ", log slider" : "")));
    } else if (control === "channels") {
      const perChannel = Array.isArray(values[p.name]);
      const boxes = element("div", { class: "channels" });
      const count = perChannel ? values[p.name].length : 1;
      for (let c = 0; c < count; c++) {
        const name = perChannel ? "RGB"[c] || String(c) : "";
        const box = element("input", { type: "number", step: "any", min: p.minimum ?? "", max: p.maximum ?? "",
          id: c === 0 ? id : id + "-" + name, "data-testid": id + (perChannel ? "-" + name : "-value"),
          "aria-label": p.name + (perChannel ? " " + name : ""), title: name ? name + " channel" : p.name });
        const current = () => (perChannel ? values[p.name][c] : values[p.name]);
        box.value = formatNumber(current());
        box.addEventListener("change", () => {
          const value = Number(box.value);
          if (box.value.trim() === "" || !Number.isFinite(value)) { box.value = formatNumber(current()); return; }
          if (perChannel) values[p.name] = values[p.name].map((v, k) => (k === c ? value : v));
          else values[p.name] = value;
          schedule();
        });
        boxes.append(perChannel ? element("span", { class: "channel" }, name) : "", box);
      }
      row.append(boxes, element("small", { class: "range" }, range + (perChannel ? " per channel (R, G, B)" : "")));
    } else if (control === "switch") {
      const label = element("label", { class: "switch", title: p.description || "" });
      const box = element("input", { type: "checkbox", role: "switch", id, "data-testid": id });
      const shown = element("span", { class: "switch-state", "data-testid": id + "-state" });
      const show = () => { shown.textContent = box.checked ? "on" : "off"; };
      box.checked = values[p.name];
      show();
      box.addEventListener("change", () => { values[p.name] = box.checked; show(); schedule(); });
      label.append(box, element("span", { class: "switch-name" }, p.name), shown);
      row.classList.add("switch-row");
      row.append(label);
      if (p.description) row.append(element("small", { class: "range" }, p.description));
    } else if (control === "colour") {
      const picker = element("input", { type: "color", id, "data-testid": id });
      picker.value = rgbToHex(values[p.name]);
      const shown = element("small", { class: "range" }, values[p.name].map(formatNumber).join(", "));
      picker.addEventListener("input", () => {
        values[p.name] = hexToRGB(picker.value);
        shown.textContent = values[p.name].map(formatNumber).join(", ");
        schedule();
      });
      row.append(picker, shown);
    } else {
      const menu = element("select", { id, "data-testid": id });
      for (const choice of p.choices || []) menu.append(element("option", { value: choice }, choice));
      menu.value = values[p.name];
      menu.addEventListener("change", () => { values[p.name] = menu.value; schedule(); });
      row.append(menu);
    }
    container.append(row);
  }
  return values;
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
  const body = { model: state.modelId, params: state.values, view: state.view, phi: state.phi,
                 convention: state.convention, quality, client: state.client, generation };
  if (state.overlay.on && state.overlay.description) {
    body.overlay = { model: state.overlay.modelId, params: state.overlay.values };
  }
  return body;
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
  const same = ["model", "view", "convention", "quality", "generation"].every((key) => body[key] === first[key])
    && body.phi === 0 && !body.overlay;
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
    clearReadouts();
    setStatus("error: nothing computed for these inputs", "failed");
    return false;
  }
  state.requestError = null;
  showErrors();
  await render(response.data, generation);
  return generation === state.generation;
}

const READOUTS = { albedo: "readout-albedo", factor_normal: "readout-factor-normal",
                   factor_max: "readout-factor-max", factor_view: "readout-factor-view", energy: "readout-energy" };

// An input the server refused: no number on screen belongs to these inputs, so none stays (nor the verdict);
// the plots stay, greyed and marked as the last accepted inputs'.
function clearReadouts() {
  for (const id of [...Object.values(READOUTS), "readout-overlay"]) {
    const node = $(id);
    node.textContent = "—";
    node.dataset.quality = "none";
    delete node.dataset.value;
  }
  $("readout-energy").dataset.status = "withdrawn";
  $("readout-energy").title = "no verdict: the inputs were refused";
  $("readout-energy-command").textContent = "";
  $("argmax").textContent = "";
  $("quality").textContent = "none: the inputs were refused";
  $("plots").classList.add("stale");
  $("plots").dataset.stale = "true";
}

async function render(data, generation) {
  const readouts = data.readouts;
  $("plots").classList.remove("stale");
  delete $("plots").dataset.stale;
  for (const [key, id] of Object.entries(READOUTS)) {
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
  const overlay = $("readout-overlay");
  overlay.textContent = data.overlay ? `${data.overlay.label}: E(θ_o) = ${data.overlay.albedo.text}, `
    + `α (${data.convention}) = ${data.overlay.factor.text}` : "—";
  overlay.dataset.quality = data.overlay ? data.quality : "none";
  overlay.dataset.generation = String(generation);
  state.lastData = data;
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

// -- models and live files ---------------------------------------------------------------------------------------
async function selectModel(id, keepValues) {
  state.requestedModel = id;
  const first = id === firstView.model && !keepValues && state.modelId === null ? await firstView.description : null;
  const description = first || await getJSON("/api/models/" + encodeURIComponent(id));
  if (state.requestedModel !== id) return;  // another model was picked meanwhile: its answer decides
  const previous = keepValues ? { ...state.values } : null;
  state.modelId = id;
  state.description = description;
  state.modelLabel = description.label || id;
  $("formula").textContent = description.formula;
  buildControls(description, previous, $("params"), state.values, "param-");
  buildFitControls(description);
  state.fileError = description.error ? description.error.text : null;
  showErrors();
  schedule();
}

async function selectOverlay(id) {
  state.overlay.requested = id;
  const description = await getJSON("/api/models/" + encodeURIComponent(id));
  const o = state.overlay;
  if (o.requested !== id) return;  // another model was picked meanwhile: its answer decides
  o.modelId = id;
  o.description = description;
  o.label = description.label;
  buildControls(description, null, $("overlay-params"), o.values, "overlay-param-");
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
  const azimuth = $("view-azimuth");
  const azimuthBox = $("view-azimuth-value");
  azimuth.addEventListener("input", () => {
    state.phi = Number(azimuth.value);
    azimuthBox.value = azimuth.value;
    schedule();
  });
  azimuthBox.addEventListener("change", () => {
    const value = Number(azimuthBox.value);
    if (azimuthBox.value.trim() === "" || !(value >= 0 && value <= 360)) {
      azimuthBox.value = String(state.phi);
      return;
    }
    state.phi = value;
    azimuth.value = String(value);
    schedule();
  });
  const toggle = (id, key, redraw) => {
    const box = $(id);
    box.checked = state[key];
    const show = () => { $(id + "-state").textContent = box.checked ? "on" : "off"; };
    show();
    box.addEventListener("change", () => { state[key] = box.checked; show(); redraw(); });
  };
  const redraw = () => { if (state.lastData) { plotLobe(state.lastData); plotAlbedo(state.lastData); } };
  toggle("log-scale", "logScale", redraw);
  toggle("raw-f", "rawF", redraw);
  const overlayPicker = $("overlay-model");
  overlayPicker.append(...[...picker.children].map((node) => node.cloneNode(true)));
  overlayPicker.value = catalog.models.find((m) => m.id !== picker.value)?.id ?? picker.value;
  toggle("overlay-on", "overlayOn", () => {
    state.overlay.on = state.overlayOn;
    overlayPicker.disabled = !state.overlay.on;
    if (state.overlay.on && !state.overlay.description) selectOverlay(overlayPicker.value);
    else schedule();
  });
  overlayPicker.disabled = true;
  overlayPicker.addEventListener("change", () => selectOverlay(overlayPicker.value));
  $("fit-parameter").addEventListener("change", setFitRange);
  enableTurning();
  $("fit-run").addEventListener("click", runFit);
  $("fit-copy").addEventListener("click", copyCode);
  listen();
  await selectModel(picker.value, false);
}

start().catch((error) => { state.requestError = "cannot start: " + error.message; showErrors(); });
