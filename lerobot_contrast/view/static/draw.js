// Shared drawing: elements, outcomes, marked instructions, top-down scenes and line charts (uPlot).
"use strict";

const SVGNS = "http://www.w3.org/2000/svg";
const COLOURS = { red: "#d32f2f", blue: "#1976d2", green: "#388e3c", yellow: "#fbc02d", orange: "#f57c00", purple: "#7b1fa2" };

function el(tag, attrs, ...children) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs || {})) {
    if (key === "class") node.className = value;
    else if (key.startsWith("on")) node.addEventListener(key.slice(2), value);
    else if (value !== null && value !== undefined && value !== false) node.setAttribute(key, value);
  }
  for (const child of children.flat(Infinity)) {
    if (child !== null && child !== undefined) node.append(child instanceof Node ? child : String(child));
  }
  return node;
}

function svg(tag, attrs, ...children) {
  const node = document.createElementNS(SVGNS, tag);
  for (const [key, value] of Object.entries(attrs || {})) node.setAttribute(key, value);
  for (const child of children.flat(Infinity)) if (child) node.append(child);
  return node;
}

// Load a data script (a page opened from disk may not fetch()); it calls viewData or viewEpisode.
function loadScript(src) {
  return new Promise((resolve, reject) => {
    const tag = document.createElement("script");
    tag.src = src;
    tag.onload = () => { tag.remove(); resolve(); };
    tag.onerror = () => { tag.remove(); reject(new Error("cannot load " + src)); };
    document.body.append(tag);
  });
}

function outcome(trial) {
  if (!trial) return el("span", { class: "other" }, "-");
  if (trial.status !== "done") return el("span", { class: "other", title: trial.status }, trial.status.replace("_", " "));
  const text = trial.success ? "success" : "failure";
  const spl = trial.spl === null ? "" : ` (SPL ${trial.spl.toFixed(3)})`;
  const said = el("span", { class: trial.success ? "ok" : "fail", "data-outcome": text }, text + spl);
  return trial.audit === null || trial.audit === undefined ? said : el("span", {}, said, " ", auditBadge(trial));
}

function auditBadge(trial) {
  const agree = Boolean(trial.audit) === Boolean(trial.success);
  const person = trial.audit ? "success" : "failure";
  return el("span", { class: "audit" + (agree ? "" : " disagree"), "data-audit": person,
    title: "drawn for the audit: a person labelled it too" }, agree ? "audited ✓" : `audit: person says ${person}`);
}

function flipBadge(original, perturbed) {
  if (!original || !perturbed || original.status !== "done" || perturbed.status !== "done") return null;
  if (Boolean(original.success) === Boolean(perturbed.success)) return null;
  return el("span", { class: "flip" + (perturbed.success ? " up" : ""), title: "the outcome flipped" },
    perturbed.success ? "flip ✗→✓" : "flip ✓→✗");
}

function marked(segments) {
  return el("span", {}, segments.map(([text, changed], k) => [
    k ? " " : "", changed ? el("mark", {}, text) : text]));
}

function markedGone(segments) {
  return el("span", {}, segments.map(([text, changed], k) => [
    k ? " " : "", changed ? el("mark", { class: "gone" }, text) : text]));
}

function colourOf(name) {
  const word = Object.keys(COLOURS).find((c) => name.includes(c));
  return word ? COLOURS[word] : "#777";
}

// A top-down view of a scene (robot frame: x forward drawn up, y left drawn left), with moves as arrows.
function sceneView(scene, options) {
  const { moved = [], target = null, size = 150, ghost = null, marks = [] } = options || {};
  const points = [];
  for (const s of [scene, ghost]) if (s) for (const p of Object.values(s.objects)) points.push(p);
  for (const m of moved) for (const p of [m.from, m.to]) if (p) points.push(p);
  if (!points.length) return el("span", { class: "muted" }, "no scene");
  const xs = points.map((p) => p[0]), ys = points.map((p) => p[1]);
  const pad = 0.05, x0 = Math.min(...xs) - pad, x1 = Math.max(...xs) + pad, y0 = Math.min(...ys) - pad, y1 = Math.max(...ys) + pad;
  const span = Math.max(x1 - x0, y1 - y0), scale = size / span;
  const at = (p) => [(y1 - p[1]) * scale, (x1 - p[0]) * scale];
  const root = svg("svg", { class: "scene", width: size, height: size, viewBox: `0 0 ${size} ${size}` });
  root.append(svg("defs", {}, svg("marker", { id: "arrow", viewBox: "0 0 10 10", refX: 9, refY: 5, markerWidth: 6, markerHeight: 6, orient: "auto" },
    svg("path", { d: "M0,0 L10,5 L0,10 z", fill: "#333" }))));
  const radius = Math.max(0.018 * scale, 3);
  if (ghost) for (const [name, p] of Object.entries(ghost.objects)) {
    const [cx, cy] = at(p);
    root.append(svg("circle", { cx, cy, r: radius, fill: "none", stroke: colourOf(name), "stroke-dasharray": "2,2" }));
  }
  for (const [name, p] of Object.entries(scene ? scene.objects : {})) {
    const [cx, cy] = at(p);
    const dot = svg("circle", { cx, cy, r: radius, fill: colourOf(name), stroke: name === target ? "#000" : "none", "stroke-width": 2 });
    dot.append(svg("title", {}, document.createTextNode(name)));
    root.append(dot);
  }
  for (const m of moved) {
    if (m.from && m.to) {
      const [ax, ay] = at(m.from), [bx, by] = at(m.to);
      root.append(svg("line", { x1: ax, y1: ay, x2: bx, y2: by, stroke: "#333", "stroke-width": 1.5, "marker-end": "url(#arrow)" }));
    }
  }
  for (const mark of marks) {
    const [cx, cy] = at(mark.at);
    root.append(svg("rect", { x: cx - radius * 1.6, y: cy - radius * 1.6, width: radius * 3.2, height: radius * 3.2, fill: "none", stroke: mark.colour, "stroke-width": 1.5 }));
    const label = svg("text", { x: cx + radius * 1.8, y: cy + 3 });
    label.textContent = mark.label;
    root.append(label);
  }
  return root;
}

function movedText(moved) {
  if (!moved.length) return el("span", { class: "muted" }, "no object moved");
  return el("span", {}, moved.map((m, k) => [k ? "; " : "",
    m.distance === null ? `${m.name} ${m.from ? "taken away" : "brought in"}` : `${m.name} ${(m.distance * 100).toFixed(1)} cm`]));
}

// A line chart of series against x, with a vertical cursor the caller may move (chart.setCursor).
function lineChart(title, x, series, options) {
  const { width = 420, height = 180, xLabel = "", yLabel = "" } = options || {};
  const palette = ["#1976d2", "#d32f2f", "#388e3c", "#f57c00", "#7b1fa2", "#00838f", "#5d4037", "#c2185b"];
  const box = el("div", { class: "chart" });
  const opts = {
    title, width, height,
    scales: { x: { time: false } },
    axes: [{ label: xLabel }, { label: yLabel }],
    series: [{ label: xLabel }, ...series.map((s, k) => ({ label: s.label, stroke: palette[k % palette.length], width: 1.5, spanGaps: false }))],
  };
  box.chart = new uPlot(opts, [x, ...series.map((s) => s.values)], box);
  return box;
}
