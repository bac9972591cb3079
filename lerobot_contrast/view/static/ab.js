// Two policies on the same plan (an A/B session, or two runs of one plan): per base, each planned trial's outcome
// under both, and a click opens both episodes side by side.
"use strict";

const abFilters = { differ: false };

function abPage(runA, runB) {
  const a = view.runs[runA], b = view.runs[runB];
  const key = (t) => `${t.instance_id}/${t.repeat}`;
  const inB = Object.fromEntries(b.trials.filter((t) => t.instance_id).map((t) => [key(t), t]));
  const columns = [...new Set(a.trials.map((t) => t.perturbation || "original"))];
  const bases = new Map();
  for (const t of a.trials) {
    if (!t.instance_id || !inB[key(t)]) continue;
    if (!bases.has(t.base_id)) bases.set(t.base_id, {});
    bases.get(t.base_id)[t.perturbation || "original"] = [t, inB[key(t)]];
  }
  const page = el("div", { id: "ab" }, el("h2", {}, `${a.policy} (${a.name}) beside ${b.policy} (${b.name})`));
  for (const session of view.doc.sessions.filter((s) => s.policies.some((p) => p.run === runA) && s.policies.some((p) => p.run === runB))) {
    page.append(verdictTable(session));
  }
  page.append(el("p", { class: "muted" }, "Each cell: the first policy's outcome, then the second's (✓ success, ✗ failure); a cell where they differ is shaded. Click a cell to open both episodes."));
  page.append(el("div", { class: "filters" }, check("disagreements only", abFilters.differ, (v) => { abFilters.differ = v; route(); })));
  const mark = (t) => (t.status !== "done" ? "·" : t.success ? "✓" : "✗");
  const rows = [];
  for (const [base, cells] of bases) {
    const differ = (pair) => pair && pair[0].status === "done" && pair[1].status === "done" && Boolean(pair[0].success) !== Boolean(pair[1].success);
    if (abFilters.differ && !Object.values(cells).some(differ)) continue;
    rows.push(el("tr", {}, el("td", {}, base), columns.map((c) => {
      const pair = cells[c];
      if (!pair) return el("td", { class: "muted" }, "");
      return el("td", { class: "cell" + (differ(pair) ? " differ" : ""), onclick: () => { location.hash = `#/pair/${runA}/${pair[0].index}/${runB}/${pair[1].index}`; } },
        `${mark(pair[0])} ${mark(pair[1])}`);
    })));
  }
  page.append(el("table", { id: "ab-table" }, el("tr", {}, el("th", {}, "base"), columns.map((c) => el("th", {}, c === "original" ? c : label(c)))), rows));
  return page;
}
