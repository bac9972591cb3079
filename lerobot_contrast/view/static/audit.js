// The audit page (#/audit/<run>): each trial the audit drew (--arm.audit_at=viewer) and not yet labelled, its
// episode played once, then a person's label from the keyboard (s: success, f: failure, r: replay). The camera's
// label is not shown: the person labels what they see. Each label is kept in the run's audit.jsonl by the server,
// with the seconds from the video's end to the key.
"use strict";

function auditCounts(run) {
  const drawn = run.trials.filter((t) => t.audit_drawn);
  const todo = drawn.filter((t) => t.audit === null || t.audit === undefined);
  return { drawn, todo };
}

function auditLink(run) {
  const { drawn, todo } = auditCounts(run);
  if (!drawn.length) return null;
  return el("p", {}, el("a", { href: `#/audit/${run.id}`, class: "audit-link" },
    `${run.name}: audit page, ${todo.length} of ${drawn.length} drawn trials still to label`));
}

// Whether the audit page shows a trial still to label: a refresh (a session still running) leaves it playing.
function auditStillOpen() {
  const audit = view.audit;
  if (!location.hash.startsWith("#/audit/") || !audit || !document.body.contains(audit.media)) return false;
  const trial = trialOf(audit.runId, audit.state.trial.index);
  return Boolean(trial) && (trial.audit === null || trial.audit === undefined);
}

function auditPage(runId) {
  const run = view.runs[runId];
  const { drawn, todo } = auditCounts(run);
  const page = el("div", { id: "audit" }, el("p", {}, el("a", { href: "#/" }, "← back to the overview")),
    el("h2", {}, `Audit: ${run.name}`),
    el("p", { class: "intro" }, `${drawn.length} trials drawn for the audit, ${todo.length} still to label. Watch the episode, then press s (success) or f (failure) for what the robot did; r plays it again. The camera's label is not shown.`));
  if (location.protocol === "file:") {
    page.append(el("p", { class: "absent" }, "Labels are kept by the served viewer only: python -m lerobot_contrast.view RUN_DIR."));
    return page;
  }
  if (!todo.length) {
    page.append(el("p", { id: "audit-done" }, "Nothing left to label."));
    return page;
  }
  const trial = todo[0];
  const state = { trial, ended: null, sent: false };
  const status = el("p", { id: "audit-status", class: "muted" }, "loading the episode…");
  const media = el("div", { class: "media" });
  page.append(el("h3", { "data-trial": trial.index }, `trial ${trial.index} (${trial.base_id}, ${label(trial.perturbation || "original")})`),
    el("p", {}, `instruction: ${trial.instruction}`), media, status,
    el("div", { class: "audit-keys" },
      el("button", { id: "audit-success", onclick: () => auditSend(runId, state, true, status) }, "success (s)"),
      el("button", { id: "audit-failure", onclick: () => auditSend(runId, state, false, status) }, "failure (f)"),
      el("button", { onclick: () => auditReplay(media, state) }, "replay (r)")));
  page.append(el("h3", {}, "Still to label"), el("ul", { id: "audit-todo" }, todo.map((t) => el("li", { "data-trial": t.index },
    `trial ${t.index}: ${t.base_id}, ${label(t.perturbation || "original")}${t === trial ? " (now)" : ""}`))));
  view.audit = { runId, state, media, status };
  episodeOf(runId, trial).then((episode) => auditShow(media, status, run, episode, state));
  return page;
}

function auditShow(media, status, run, episode, state) {
  if (!episode) {
    media.replaceChildren(el("p", { class: "absent" }, run.videos_absent ? `Videos absent: ${run.videos_absent}.` : "This trial has no recorded episode."));
    state.ended = performance.now();
    status.textContent = "label it from the Rerun recording or from what you saw at the bench: s or f";
    return;
  }
  const clips = episode.videos.map((v) => {
    const video = el("video", { muted: true, playsinline: true, preload: "auto", src: run.video_base + v.path, "data-key": v.key });
    video.muted = true;
    return { video, start: v.span[0], end: v.span[1] };
  });
  media.replaceChildren(...clips.map((c) => c.video));
  media.clips = clips;
  status.textContent = "playing the episode…";
  auditReplay(media, state);
}

function auditReplay(media, state) {
  const clips = media.clips || [];
  let left = clips.length;
  for (const clip of clips) {
    const { video } = clip;
    const finish = () => {
      if (video.dataset.done === "1") return;
      video.dataset.done = "1";
      video.pause();
      left -= 1;
      if (left === 0) {
        state.ended = performance.now();
        const status = document.getElementById("audit-status");
        if (status) status.textContent = "the episode ended: s (success) or f (failure)";
      }
    };
    video.dataset.done = "0";
    video.ontimeupdate = () => { if (video.currentTime >= clip.end - 0.03) finish(); };
    video.onended = finish;
    const start = () => { video.currentTime = clip.start; video.play().catch(finish); };
    if (video.readyState >= 1) start(); else video.onloadedmetadata = start;
  }
}

function auditSend(runId, state, success, status) {
  if (state.sent) return;
  state.sent = true;
  const seconds = state.ended === null ? null : (performance.now() - state.ended) / 1000;
  fetch(`audit/${runId}`, { method: "POST", headers: { "Content-Type": "application/json" },
    body: JSON.stringify({ trial: state.trial.index, success, seconds }) })
    .then((response) => response.json().then((answer) => ({ ok: response.ok, answer })))
    .then(({ ok, answer }) => {
      if (!ok) { state.sent = false; status.textContent = `not kept: ${answer.error}`; status.className = "absent"; return; }
      status.textContent = `kept: trial ${state.trial.index} ${success ? "success" : "failure"}`;
      refresh();  // the run's document comes back with the label, and the page moves to the next trial
    })
    .catch((error) => { state.sent = false; status.textContent = `not kept: ${error.message}`; status.className = "absent"; });
}

document.addEventListener("keydown", (event) => {
  const audit = view.audit;
  if (!audit || !document.body.contains(audit.media) || event.ctrlKey || event.metaKey || event.altKey) return;
  if (event.key === "s") auditSend(audit.runId, audit.state, true, audit.status);
  else if (event.key === "f") auditSend(audit.runId, audit.state, false, audit.status);
  else if (event.key === "r") auditReplay(audit.media, audit.state);
});
