// A pair opened: both episodes' videos side by side and in step, their actions and states plotted under them,
// each trial's start scene and, where the run checked its staging with a calibrated camera, that check.
"use strict";

function viewEpisode(episode) {
  view.episodes[`${episode.run}/${episode.episode}`] = episode;
}

function stagingView(trial) {
  const check = trial.staging_check;
  if (!check) return null;
  const marks = Object.entries(check.off_m || {}).filter(([name]) => trial.scene.objects[name]).map(([name, off]) => ({
    at: trial.scene.objects[name], colour: off === 0 ? "#2e7d32" : "#c62828",
    label: off === 0 ? "ok" : off === null ? "not seen" : `${(off * 100).toFixed(1)} cm off`,
  }));
  const moved = Object.entries(check.placed || {}).filter(([name]) => check.before[name])
    .map(([name, to]) => ({ name, from: check.before[name], to }));
  return el("div", { class: "staging" }, el("h3", {}, "Staging check (the camera's measurement)"),
    el("p", { class: "muted" }, `targets as squares, where the objects were before staging dashed; moved ${check.moved_m.toFixed(3)} m, tolerance ${(check.tolerance_m * 100).toFixed(1)} cm`),
    sceneView(trial.scene, { moved, marks, ghost: { objects: check.before }, size: 220 }));
}

function side(runId, trial, moved, title) {
  const run = view.runs[runId];
  const column = el("div", { class: "column", "data-trial": trial.index });
  column.append(el("h3", {}, title), el("p", {}, outcome(trial), ` · cost paid ${trial.cost === null ? "-" : trial.cost.toFixed(2)} ${run.cost_unit} · ${trial.steps === null ? "-" : trial.steps} steps`));
  column.append(el("div", { class: "media" }, run.videos_absent ? el("p", { class: "absent" }, `Videos absent: ${run.videos_absent}.`) : el("p", { class: "muted" }, "loading the episode…")));
  column.append(el("div", { class: "charts" }));
  column.append(el("h3", {}, "Start scene (top-down; x forward up)"), sceneView(trial.scene, { moved, target: trial.target, size: 220 }), el("p", {}, movedText(moved)));
  const staging = stagingView(trial);
  if (staging) column.append(staging);
  return column;
}

function pairPage(runA, indexA, runB, indexB) {
  const a = trialOf(runA, indexA), b = trialOf(runB, indexB);
  const page = el("div", { id: "pair" });
  if (!a || !b) return el("p", {}, "No such trial.");
  const pair = runA === runB ? view.runs[runA].pairs.find((p) => p.perturbed === b.index && p.original === a.index) : null;
  const abPair = runA !== runB;
  const back = abPair ? `#/ab/${runA}/${runB}` : `#/p/${runA}/${b.perturbation || "all"}`;
  page.append(el("p", {}, el("a", { href: back }, "← back to the list")));
  page.append(el("h2", {}, `${b.base_id}: ${abPair ? `${label(b.perturbation || "original")}, policy beside policy` : `original beside ${label(b.perturbation)}`}`, " ", flipBadge(a, b)));
  if (pair) page.append(el("p", {}, "original: ", markedGone(pair.words[0]), el("br"), "perturbed: ", marked(pair.words[1])));
  else page.append(el("p", {}, `instruction: ${b.instruction}`));
  const titles = abPair ? [view.runs[runA].policy, view.runs[runB].policy] : ["original", label(b.perturbation)];
  const columns = [side(runA, a, [], titles[0]), side(runB, b, pair ? pair.moved : [], titles[1])];
  const controls = el("div", { class: "controls" });
  page.append(controls, el("div", { class: "columns" }, columns));
  Promise.all([[runA, a], [runB, b]].map(([r, t]) => episodeOf(r, t))).then((episodes) => play(controls, columns, [runA, runB], episodes));
  return page;
}

function episodeOf(runId, trial) {
  const run = view.runs[runId];
  if (run.videos_absent || trial.episode === null) return Promise.resolve(null);
  const key = `${runId}/${trial.episode}`;
  if (view.episodes[key]) return Promise.resolve(view.episodes[key]);
  return loadScript(`data/episodes/${runId}/${trial.episode}.js`).then(() => view.episodes[key], () => null);
}

function play(controls, columns, runIds, episodes) {
  const clips = [], charts = [];
  episodes.forEach((episode, k) => {
    const media = columns[k].querySelector(".media"), box = columns[k].querySelector(".charts");
    if (!episode) {
      if (!view.runs[runIds[k]].videos_absent) media.replaceChildren(el("p", { class: "absent" }, "This trial has no recorded episode."));
      return;
    }
    media.replaceChildren(...episode.videos.map((v) => {
      const video = el("video", { muted: true, playsinline: true, preload: "auto", src: view.runs[runIds[k]].video_base + v.path, "data-key": v.key });
      video.muted = true;
      video.addEventListener("loadedmetadata", () => { video.currentTime = v.span[0]; });
      clips.push({ video, start: v.span[0], length: v.span[1] - v.span[0] });
      return video;
    }));
    for (const signal of episode.signals) {
      const chart = lineChart(signal.name, signal.time, signal.labels.map((l, i) => ({ label: l, values: signal.series[i] })), { width: Math.max(260, (box.clientWidth || 600) / 2 - 12), height: 170, xLabel: "time (s)" });
      charts.push(chart.chart);
      box.append(chart);
    }
  });
  if (!clips.length) return;
  const length = Math.max(...clips.map((c) => c.length));
  const clock = { t: 0, playing: false, last: 0 };
  const slider = el("input", { type: "range", min: 0, max: length, step: 0.01, value: 0, oninput: (e) => { clock.t = +e.target.value; } });
  const button = el("button", { id: "play", onclick: () => {
    if (clock.t >= length) clock.t = 0;
    clock.playing = !clock.playing; clock.last = performance.now();
  } }, "play");
  const time = el("span", { class: "muted" });
  controls.replaceChildren(button, slider, time);
  function tick(now) {
    if (!document.body.contains(slider)) { clips.forEach((c) => c.video.pause()); return; }
    if (clock.playing) {
      clock.t = Math.min(clock.t + (now - clock.last) / 1000, length);
      if (clock.t >= length) clock.playing = false;
    }
    clock.last = now;
    for (const c of clips) {
      const target = c.start + Math.min(clock.t, c.length - 0.001);
      const running = clock.playing && clock.t < c.length;
      if (running && c.video.paused) c.video.play().catch(() => {});
      if (!running && !c.video.paused) c.video.pause();
      if (c.video.readyState >= 1 && Math.abs(c.video.currentTime - target) > (running ? 0.25 : 0.02)) c.video.currentTime = target;
    }
    slider.value = clock.t;
    button.textContent = clock.playing ? "pause" : "play";
    time.textContent = `${clock.t.toFixed(2)} / ${length.toFixed(2)} s`;
    for (const chart of charts) chart.setCursor({ left: chart.valToPos(clock.t, "x"), top: 5 });
    requestAnimationFrame(tick);
  }
  requestAnimationFrame(tick);
  view.clock = clock;
}
