// The page's state and router, and the overview: settings, the report's tables, the curves and the A/B sessions.
"use strict";

const view = { doc: null, runs: {}, byIndex: {}, episodes: {}, timer: null };

// Called by data/runs.js, at load and at each refresh of a run in progress.
function viewData(doc) {
  const first = view.doc === null;
  if (!first && doc.stamp === view.doc.stamp) return;
  view.doc = doc;
  view.runs = Object.fromEntries(doc.runs.map((r) => [r.id, r]));
  view.byIndex = Object.fromEntries(doc.runs.map((r) => [r.id, Object.fromEntries(r.trials.map((t) => [t.index, t]))]));
  document.getElementById("title").textContent = doc.runs.map((r) => r.name).join(" · ");
  document.getElementById("live").hidden = !doc.live;
  if (doc.live && !view.timer) view.timer = setInterval(refresh, 2000);
  if (!doc.live && view.timer) { clearInterval(view.timer); view.timer = null; }
  if (first || !(location.hash.startsWith("#/pair/") || auditStillOpen())) route();  // an open pair keeps playing
}

function refresh() {
  loadScript("data/runs.js?t=" + Date.now()).catch(() => {});
}

function trialOf(runId, index) {
  return (view.byIndex[runId] || {})[index];
}

function route() {
  const main = document.getElementById("main");
  const scroll = window.scrollY;
  const parts = location.hash.replace(/^#\/?/, "").split("/").map(decodeURIComponent);
  let page;
  if (parts[0] === "p" && view.runs[parts[1]]) page = pairsPage(parts[1], parts[2] || "all");
  else if (parts[0] === "pair" && view.runs[parts[1]] && view.runs[parts[3]]) page = pairPage(parts[1], +parts[2], parts[3], +parts[4]);
  else if (parts[0] === "ab" && view.runs[parts[1]] && view.runs[parts[2]]) page = abPage(parts[1], parts[2]);
  else if (parts[0] === "audit" && view.runs[parts[1]]) page = auditPage(parts[1]);
  else page = overview();
  main.replaceChildren(page);
  main.dataset.page = parts[0] || "overview";
  window.scrollTo(0, view.lastHash === location.hash ? scroll : 0);
  view.lastHash = location.hash;
}
window.addEventListener("hashchange", route);

function reportTable(table, onRow) {
  const head = el("tr", {}, table.header.map((h) => el("th", {}, h)));
  const rows = table.rows.map((row, k) => {
    const key = table.keys[k];
    const attrs = onRow && key ? { class: "link", "data-key": key, onclick: () => onRow(key) } : {};
    return el("tr", attrs, row.map((cell) => el("td", {}, cell)));
  });
  return el("section", { class: "report-table", "data-title": table.title },
    el("h2", {}, table.title), el("p", { class: "intro" }, table.intro), el("table", {}, el("thead", {}, head), el("tbody", {}, rows)));
}

function settingsBlock(run) {
  const rows = Object.entries(run.settings).map(([k, v]) => el("tr", {}, el("td", {}, k), el("td", {}, typeof v === "object" ? JSON.stringify(v) : String(v))));
  return el("details", {}, el("summary", {}, `${run.name}: ${run.policy}, ${run.strategy}, ${run.complete ? "complete" : "incomplete (stopped early, or still running)"}`),
    el("p", { class: "muted" }, run.path), el("table", {}, el("tbody", {}, rows)));
}

function curvesBlock() {
  const runs = view.doc.runs.filter((r) => r.curves.cost.length);
  if (!runs.length) return el("p", { class: "muted" }, "No trial has been done yet.");
  const unit = runs[0].cost_unit, metric = view.doc.report.metric_name;
  const charts = el("div", { class: "charts" });
  // Each run on its own cost axis: uPlot wants one x array per chart, so one chart per run.
  for (const run of runs) {
    const label = runs.length > 1 ? `${run.name}: ` : "";
    charts.append(lineChart(`${label}done trials against cost`, run.curves.cost, [{ label: "trials", values: run.curves.trials }], { xLabel: `cost (${unit})`, yLabel: "trials" }));
    charts.append(lineChart(`${label}running ${metric} estimate against cost`, run.curves.cost, [{ label: metric, values: run.curves.estimate }], { xLabel: `cost (${unit})`, yLabel: metric }));
  }
  return el("section", {}, el("h2", {}, "Cost and estimate"),
    el("p", { class: "intro" }, `Done trials within each cost, and the mean ${metric} over them (as report's figures compute them).`), charts);
}

function abBlock() {
  const doc = view.doc;
  if (!doc.same_plan.length) return null;
  const items = doc.same_plan.map(([a, b]) => el("li", {},
    el("a", { href: `#/ab/${a}/${b}`, class: "ab-link" }, `${view.runs[a].policy} (${view.runs[a].name}) beside ${view.runs[b].policy} (${view.runs[b].name}), per base`)));
  const sessions = doc.sessions.map((s) => verdictTable(s));
  return el("section", {}, el("h2", {}, "Policies side by side"), el("ul", {}, items), sessions);
}

function verdictTable(session) {
  const pairs = (session.stopping || {}).pairs || [];
  if (!pairs.length) return el("p", { class: "muted" }, `${session.name}: no sequential decision yet.`);
  const rows = pairs.map((p) => el("tr", {}, el("td", {}, p.first), el("td", {}, p.second),
    el("td", {}, `[${p.difference_interval[0].toFixed(3)}, ${p.difference_interval[1].toFixed(3)}]`),
    el("td", { class: "verdict" }, p.verdict), el("td", {}, p.decided_at_bases === null ? "-" : String(p.decided_at_bases))));
  return el("div", {}, el("h3", {}, `${session.name}: the sequential paired test (${session.stopping.metric}): ${session.stopping.why}`),
    el("table", {}, el("tr", {}, ["first", "second", "anytime-valid interval", "verdict", "decided after bases"].map((h) => el("th", {}, h))), rows));
}

function overview() {
  const doc = view.doc, report = doc.report;
  const firstRun = doc.runs[0].id;
  const openPerturbation = (key) => { location.hash = `#/p/${firstRun}/${key === "original" ? "all" : key}`; };
  const page = el("div", { id: "overview" });
  page.append(el("h2", {}, "Runs"), ...doc.runs.map(settingsBlock));
  for (const run of doc.runs) {
    const audit = auditLink(run);
    if (audit) page.append(audit);
    if (run.videos_absent) page.append(el("p", { class: "absent" }, `${run.name}: ${run.videos_absent}.`));
    if (run.journal_absent) page.append(el("p", { class: "absent" }, `${run.name}: ${run.journal_absent}.`));
  }
  for (const table of report.tables) page.append(reportTable(table, table.keys.length ? openPerturbation : null));
  page.append(el("p", {}, el("a", { href: `#/p/${firstRun}/all` }, "Every pair of every perturbation")));
  page.append(curvesBlock());
  const ab = abBlock();
  if (ab) page.append(ab);
  const notes = [...report.notes, ...doc.notes];
  if (notes.length) page.append(el("h2", {}, "Notes"), el("ul", {}, notes.map((n) => el("li", {}, n))));
  return page;
}
