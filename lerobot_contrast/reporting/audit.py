"""The report's section on labels the arm's camera gave (--operator=arm): with an audit (--arm.audit), the success
rate and each perturbation's paired change as prediction-powered estimates beside the camera's own, the camera
against the person on the audited trials, and the camera's estimated error; without one, that the rates take the
camera's labels as right."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd

from lerobot_contrast.contrast import audited
from lerobot_contrast.record.audit_labels import drawn, read_labels
from lerobot_contrast.reporting import stats
from lerobot_contrast.reporting.markdown import num, perturbation_name, table
from lerobot_contrast.reporting.runs import Run

SEQUENTIAL = (
    "A sequential stopping rule (--stop.*) reads the run's labels as they come and not the audit: its decisions "
    "take the camera's labels as right; read the audited interval beside it."
)


def labelled(run: Run, later: dict[int, dict]) -> pd.DataFrame:
    """The run's done trials with `label` (0/1, the run's label), `drawn` (for the audit), `audited` (labelled by a
    person: at the bench, in the journal, or later in the viewer: `later`, audit.jsonl's) and `person` (that
    label)."""
    rows = stats.done(run.results).sort_values("index")
    extra = rows["extra"].map(lambda text: json.loads(text) if isinstance(text, str) and text else {})
    person = [e.get("audit", later.get(int(i), {}).get("success")) for e, i in zip(extra, rows["index"], strict=True)]
    person = pd.Series(person, index=rows.index, dtype=object)
    return rows.assign(label=rows["success"].astype(float), audited=person.notna(),
                       drawn=extra.map(drawn),
                       person=person.map(lambda said: np.nan if said is None else float(said)))  # fmt: skip


def audit_section(runs: list[Run]) -> list[str]:
    arm = [run for run in runs if run.config.get("operator") == "arm"]
    if not arm:
        return []
    lines = ["## Labels the camera gave", ""]
    rows, changes, unaudited, notes = [], [], [], []
    for run in arm:
        later = read_labels(run.path)
        df = labelled(run, later)
        pace = _viewer_pace(run.name, later)
        if pace:
            notes.append(pace)
        waiting = int((df["drawn"] & ~df["audited"]).sum())
        if waiting:
            notes.append(f"{run.name}: {waiting} trial(s) drawn for the audit still wait for a person's label "
                           "(python -m lerobot_contrast.view RUN, its audit page); until then they count as unaudited.")  # fmt: skip
        if not df["audited"].any():
            unaudited.append(run.name)
            continue
        camera = stats.estimate(df["label"].to_numpy(), df["base_id"].to_numpy())
        ppi = audited.rate(df["label"], df["audited"], df["person"], df["base_id"])
        checked = df[df["audited"]]
        wrong = int((checked["label"] != checked["person"]).sum())
        rows.append([run.name, f"{len(checked)} of {len(df)}", _interval(camera.mean, camera.low, camera.high),
                     _interval(ppi.mean, ppi.low, ppi.high), num(ppi.weight, ".2f"),
                     _confusion(checked), f"{wrong / len(checked):.3f} ({wrong} of {len(checked)})"])  # fmt: skip
        changes += [[run.name, *change] for change in _changes(df)]
    if rows:
        header = ["run", "audited", "success (camera's labels)", "success (audited, PPI++)", "lambda",
                  "camera / person on the audit", "camera's error"]  # fmt: skip
        lines += table(header, rows)
        lines += ["", "Prediction-powered estimates (PPI++, Angelopoulos, Duchi and Zrnic 2023) combine every label "
                  "with a person's labels of a random audit; their 95% intervals, clustered by base, hold whatever "
                  "the camera's mistakes (scripts/bench/bench_audit.py measures their coverage). lambda near 1: the "
                  "camera agrees with the person and the interval nears the camera's own. A small audit gives a wide "
                  "interval: tens of labels cannot rule out a camera whose few mistakes lean one way "
                  "(docs/statistics.md).", ""]  # fmt: skip
    if changes:
        header = ["run", "perturbation", "bases", "change (camera's labels)", "change (audited, PPI++)"]
        lines += table(header, changes) + [""]
    lines += [line for text in notes for line in (text, "")]
    for name in unaudited:
        lines += [f"{name}: no trial was audited (--arm.audit), so its rates take every label the camera gave as "
                  "right.", ""]  # fmt: skip
    if any(run.summary.get("stopping") for run in arm):
        lines += [SEQUENTIAL, ""]
    return lines


def _viewer_pace(name: str, later: dict[int, dict]) -> str | None:
    """How long a person took per label on the viewer's audit page (`later`), from the episode's end to the key."""
    seconds = [label["seconds"] for label in later.values() if "seconds" in label]
    if not seconds:
        return None
    return (f"{name}: a person took {np.median(seconds):.1f} s per audited trial on the viewer's audit page after "
            f"its episode ended (median of {len(seconds)}; 90th percentile {np.quantile(seconds, 0.9):.1f} s).")  # fmt: skip


def _changes(df: pd.DataFrame) -> list[list[str]]:
    """Per perturbation: its paired change against the same base's original, camera-only and audited."""
    first = df.drop_duplicates(["base_id", "perturbation"]).assign(perturbation=lambda d: d["perturbation"].fillna(""))
    originals = first[first["perturbation"] == ""].set_index("base_id")
    out = []
    for name in [p for p in pd.unique(first["perturbation"]) if p]:
        perturbed = first[first["perturbation"] == name].set_index("base_id")
        bases = perturbed.index.intersection(originals.index)
        pairs = pd.concat([originals.loc[bases], perturbed.loc[bases]])
        flags = np.r_[np.zeros(len(bases), bool), np.ones(len(bases), bool)]
        ppi = audited.paired_change(pairs["label"], pairs["audited"], pairs["person"], pairs.index, flags)
        camera = float((perturbed.loc[bases, "label"] - originals.loc[bases, "label"]).mean()) if len(bases) else np.nan
        out.append([perturbation_name(name), str(len(bases)), num(camera, "+.3f"),
                    _interval(ppi.mean, ppi.low, ppi.high, "+.3f")])  # fmt: skip
    return out


def _confusion(checked: pd.DataFrame) -> str:
    both = {(c, p): int(((checked["label"] == c) & (checked["person"] == p)).sum()) for c in (1, 0) for p in (1, 0)}
    return f"S/S {both[1, 1]} · S/F {both[1, 0]} · F/S {both[0, 1]} · F/F {both[0, 0]}"


def _interval(mean: float, low: float, high: float, spec: str = ".3f") -> str:
    if np.isnan(mean):
        return "-"
    return f"{num(mean, spec)} [{num(low, spec)}, {num(high, spec)}]"
