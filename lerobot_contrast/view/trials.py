"""One run's trials for the page: each trial's outcome and start scene, each perturbed trial paired with its own
base's original (changed words, moved objects), and the cost and estimate curves by report's own functions."""

from __future__ import annotations

import difflib
from collections.abc import Sequence
from typing import Any

import numpy as np

from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.contrast.trial import TrialRecord
from lerobot_contrast.record.audit_labels import drawn
from lerobot_contrast.reporting import stats
from lerobot_contrast.reporting.runs import Run

MOVED_M = 1e-3  # an object that moved less than a millimetre between two scenes did not move


def _r(value: float | None, digits: int = 4) -> float | None:
    return None if value is None else round(float(value), digits)


def scene_json(scene: Scene | None) -> dict[str, Any] | None:
    """Objects and robot as [x, y, yaw] in metres and radians, rounded to a millimetre."""
    if scene is None:
        return None
    data = scene.to_json()
    objects = {name: [round(v, 3) for v in pose] for name, pose in data["objects"].items()}
    robot = data.get("robot")
    return {"objects": objects, "robot": None if robot is None else [round(v, 3) for v in robot]}


def word_marks(before: str, after: str) -> tuple[list[list[Any]], list[list[Any]]]:
    """Both instructions as [text, changed] segments: the words the perturbation replaced, and those it wrote."""
    a, b = before.split(), after.split()
    left: list[list[Any]] = []
    right: list[list[Any]] = []
    for tag, i1, i2, j1, j2 in difflib.SequenceMatcher(a=a, b=b, autojunk=False).get_opcodes():
        changed = tag != "equal"
        if i2 > i1:
            left.append([" ".join(a[i1:i2]), changed])
        if j2 > j1:
            right.append([" ".join(b[j1:j2]), changed])
    return left, right


def moved_objects(before: Scene | None, after: Scene) -> list[dict[str, Any]]:
    """What staging changed from `before` to `after`: each object moved (with how far), brought in or taken away."""
    if before is None:
        return []
    out = []
    for name in sorted(set(before.objects) | set(after.objects)):
        start, end = before.objects.get(name), after.objects.get(name)
        if start is None or end is None:
            out.append({"name": name, "from": _xy(start), "to": _xy(end), "distance": None})
        elif (distance := start.distance_to(end)) > MOVED_M:
            out.append({"name": name, "from": _xy(start), "to": _xy(end), "distance": round(distance, 4)})
    return out


def _xy(pose) -> list[float] | None:
    return None if pose is None else [round(pose.x, 3), round(pose.y, 3)]


def trial_json(record: TrialRecord, later: dict[str, Any] | None = None) -> dict[str, Any]:
    """`later`: a person's audit label given in the viewer (audit.jsonl), where there is one."""
    instance = record.instance
    audit = record.extra.get("audit", None if later is None else later["success"])
    return {
        "index": record.index,
        "base_id": record.base_id,
        "instance_id": record.instance_id,
        "perturbation": record.perturbation,
        "axis": record.axis,
        "family": record.family,
        "staging": record.staging,
        "repeat": record.repeat,
        "status": record.status,
        "success": record.success,
        "spl": _r(record.spl),
        "progress": _r(record.progress),
        "cost": _r(record.cost),
        "cumulative_cost": _r(record.cumulative_cost),
        "steps": record.steps,
        "episode": record.dataset_episode,
        "instruction": None if instance is None else instance.instruction,
        "target": None if instance is None else instance.goal.get("block"),
        "scene": None if instance is None else scene_json(instance.scene),
        "staging_check": record.extra.get("staging"),
        "label_asked": bool(record.extra.get("label_asked")),  # a person labelled it where the arm's camera was unsure
        "audit": audit,  # a person's label of a trial the audit drew (--arm.audit), at the bench or later, else None
        "audit_drawn": drawn(record.extra),
        "audit_seconds": None if later is None else later.get("seconds"),
    }


def staged_from(records: Sequence[TrialRecord]) -> dict[int, Scene | None]:
    """Per trial, the scene its staging started from: where the last episode left the objects (in place), or the
    base's original start scene (a reset)."""
    originals = {(r.base_id, r.repeat): r.instance.scene for r in records if r.perturbation is None and r.instance}
    left: Scene | None = None
    out: dict[int, Scene | None] = {}
    for record in sorted(records, key=lambda r: r.index):
        reset = record.staging == "reset" and record.perturbation is not None
        out[record.index] = originals.get((record.base_id, record.repeat)) if reset else left
        if record.scene_after is not None:
            left = record.scene_after
    return out


def pairs(records: Sequence[TrialRecord]) -> list[dict[str, Any]]:
    """Each perturbed trial that ran beside its base's original (the same repeat, else the first)."""
    originals: dict[str, dict[int, TrialRecord]] = {}
    for r in records:
        if r.perturbation is None and r.instance is not None:
            originals.setdefault(r.base_id, {})[r.repeat] = r
    before = staged_from(records)
    out = []
    for r in records:
        if r.perturbation is None or r.instance is None or r.base_id not in originals:
            continue
        base = originals[r.base_id].get(r.repeat) or next(iter(originals[r.base_id].values()))
        left, right = word_marks(base.instance.instruction, r.instance.instruction)
        both_done = base.status == "done" and r.status == "done"
        out.append(
            {
                "original": base.index,
                "perturbed": r.index,
                "words": [left, right],
                "moved": moved_objects(before[r.index], r.instance.scene),
                "flip": both_done and bool(base.success) != bool(r.success),
            }
        )
    return out


def curves(run: Run, metric: str) -> dict[str, list[float]]:
    """Done trials and the running estimate of `metric` against cumulative cost, as `report` computes both."""
    done = stats.done(run.results)
    costs = np.unique(done["cumulative_cost"].to_numpy(dtype=np.float64))
    estimate = stats.running_estimate(run.results, metric, costs)
    trials = stats.trials_at_cost(run.results, costs)
    return {
        "cost": [round(float(c), 4) for c in costs],
        "trials": [int(n) for n in trials],
        "estimate": [None if np.isnan(v) else round(float(v), 4) for v in estimate],
    }
