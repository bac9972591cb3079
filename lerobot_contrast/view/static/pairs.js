// A perturbation's pairs: each base's original beside its perturbed trial, what changed, both outcomes, the cost.
"use strict";

const filters = { flips: false, failures: false, axis: "", family: "", shown: 100 };

function pairRows(run, perturbation) {
  return run.pairs.filter((p) => {
    const t = trialOf(run.id, p.perturbed), o = trialOf(run.id, p.original);
    if (perturbation !== "all" && t.perturbation !== perturbation) return false;
    if (filters.flips && !p.flip) return false;
    if (filters.failures && !(t.status === "done" && !t.success) && !(o.status === "done" && !o.success)) return false;
    if (filters.axis && t.axis !== filters.axis) return false;
    if (filters.family && t.family !== filters.family) return false;
    return true;
  });
}

function choice(label, value, options, set) {
  return el("label", {}, label + " ", el("select", { onchange: (e) => set(e.target.value), "data-filter": label },
    el("option", { value: "" }, "all"), options.map((o) => el("option", { value: o, selected: o === value }, o))));
}

function check(label, value, set) {
  return el("label", {}, el("input", { type: "checkbox", checked: value, "data-filter": label, onchange: (e) => set(e.target.checked) }), " " + label);
}

function filterBar(run) {
  const again = () => { filters.shown = 100; route(); };
  const axes = [...new Set(run.trials.map((t) => t.axis).filter(Boolean))].sort();
  const families = [...new Set(run.trials.map((t) => t.family))].sort();
  return el("div", { class: "filters" },
    check("flips only", filters.flips, (v) => { filters.flips = v; again(); }),
    check("failures only", filters.failures, (v) => { filters.failures = v; again(); }),
    choice("axis", filters.axis, axes, (v) => { filters.axis = v; again(); }),
    choice("family", filters.family, families, (v) => { filters.family = v; again(); }));
}

function perturbationLinks(run, current) {
  const names = [...new Set(run.trials.map((t) => t.perturbation).filter(Boolean))];
  const runs = view.doc.runs.length > 1 ? view.doc.runs.map((r) => el("a", { href: `#/p/${r.id}/${current}`, class: r.id === run.id ? "current" : "" }, r.name)) : [];
  return el("p", {}, "Perturbation: ",
    ["all", ...names].map((n, k) => [k ? " · " : "", n === current ? el("b", {}, label(n)) : el("a", { href: `#/p/${run.id}/${n}` }, label(n))]),
    runs.length ? el("span", {}, " — run: ", runs.map((r, k) => [k ? " · " : "", r])) : null);
}

function label(name) {
  return name === "all" ? "all" : "Δ" + name;
}

function pairsPage(runId, perturbation) {
  const run = view.runs[runId];
  const rows = pairRows(run, perturbation);
  const unit = run.cost_unit;
  const page = el("div", { id: "pairs" }, el("h2", {}, `${run.name}: ${perturbation === "all" ? "every perturbation" : label(perturbation)}, each beside its base's original`));
  page.append(perturbationLinks(run, perturbation), filterBar(run));
  if (run.journal_absent) page.append(el("p", { class: "absent" }, run.journal_absent));
  const flips = rows.filter((p) => p.flip).length;
  page.append(el("p", { class: "muted", id: "pair-count" }, `${rows.length} pairs shown, ${flips} of them flipped.`));
  const head = el("tr", {}, ["base", "instruction: original / perturbed", "scene change (top-down)", "original", "perturbed", `cost paid (${unit})`, ""].map((h) => el("th", {}, h)));
  const body = rows.slice(0, filters.shown).map((p) => pairRow(run, p));
  page.append(el("table", { id: "pair-table" }, el("thead", {}, head), el("tbody", {}, body)));
  if (rows.length > filters.shown) {
    page.append(el("button", { onclick: () => { filters.shown += 200; route(); } }, `show ${Math.min(200, rows.length - filters.shown)} more of ${rows.length - filters.shown}`));
  }
  return page;
}

function pairRow(run, pair) {
  const o = trialOf(run.id, pair.original), t = trialOf(run.id, pair.perturbed);
  const href = `#/pair/${run.id}/${o.index}/${run.id}/${t.index}`;
  return el("tr", { class: "link pair", "data-perturbed": t.index, onclick: () => { location.hash = href; } },
    el("td", {}, el("b", {}, t.base_id), el("br"), el("span", { class: "muted" }, `${t.family} · ${label(t.perturbation)} · ${t.staging.replace("_", " ")}`)),
    el("td", {}, markedGone(pair.words[0]), el("br"), marked(pair.words[1])),
    el("td", {}, sceneView(t.scene, { moved: pair.moved, target: t.target, size: 110 }), el("br"), movedText(pair.moved)),
    el("td", {}, outcome(o)),
    el("td", {}, outcome(t), " ", flipBadge(o, t)),
    el("td", {}, t.cost === null ? "-" : t.cost.toFixed(2)),
    el("td", {}, el("a", { href, class: "open" }, "open")));
}
