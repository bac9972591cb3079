"""What a policy did with the recorded task's object, trial by trial, from the scripted operator's log (its "the trial
ended with ..." line: the twin's true scene, and its "... is held ... not put down" line) and the run's journal: put in
which region, still held in the gripper (wherever it hangs), moved elsewhere, or left where it was. For a
language-blind policy this shows what it keys on, beside the success rates."""

from __future__ import annotations

import json
import math
import re
from collections import Counter
from pathlib import Path

from lerobot_contrast.domains.task_file.schema import TaskSpec

ENDED = "the trial ended with "  # what the scripted operator says once a trial ends, then `name (x, y)` per object
TRIAL = re.compile(r"trial (\d+)/(\d+) · ")  # the console's header of each trial
POSE = re.compile(r"(\w+) \((-?[\d.]+), (-?[\d.]+)\)")
HELD = re.compile(r"(\w+) is held [\d.]+ cm up, not put down")
STILL_M = 0.01  # moved less than this: left where the trial started it
ELSEWHERE, UNMOVED, IN_GRIPPER = "moved elsewhere", "not moved", "held in the gripper"


def held_line(name: str, up_m: float) -> str:
    """What the scripted operator says of an object still in the gripper at the trial's end (`up_m` above its rest)."""
    return f"{name} is held {up_m * 100:.1f} cm up, not put down"


def ended_scenes(log: Path) -> tuple[dict[int, dict[str, tuple[float, float]]], dict[int, set[str]]]:
    """Each trial's (0-based index) final object positions, and the objects still held in the gripper, as the
    operator's log has them."""
    scenes, held, trial = {}, {}, None
    for line in log.read_text(errors="replace").splitlines():
        if found := TRIAL.search(line):
            trial = int(found.group(1)) - 1
        elif ENDED in line and trial is not None:
            scenes[trial] = {name: (float(x), float(y)) for name, x, y in POSE.findall(line.split(ENDED, 1)[1])}
        elif (found := HELD.search(line)) and trial is not None:
            held.setdefault(trial, set()).add(found.group(1))
    return scenes, held


def fates(run_dir: Path, log: Path, spec: TaskSpec, subject: str) -> dict[str, Counter]:
    """Per perturbation ("original" for the bases): where `subject` ended in its trials, and how many succeeded."""
    ended, held = ended_scenes(log)
    regions = {name: region for name, region in spec.workspace.regions.items() if region.center is not None}
    table: dict[str, Counter] = {}
    for line in (run_dir / "journal.jsonl").read_text().splitlines():
        record = json.loads(line)
        final = ended.get(record["index"], {}).get(subject)
        if record["status"] != "done" or final is None or record["instance"] is None:
            continue
        start = record["instance"]["scene"]["objects"][subject][:2]
        inside = [name for name, region in regions.items() if region.contains(*final)]
        if subject in held.get(record["index"], ()):
            fate = IN_GRIPPER  # x and y over a bin are not a placement
        else:
            fate = f"in {inside[0]}" if inside else UNMOVED if math.dist(final, start) < STILL_M else ELSEWHERE
        counts = table.setdefault(record["perturbation"] or "original", Counter())
        counts[fate] += 1
        counts["success"] += bool(record["success"])
        counts["trials"] += 1
    return table


def fates_markdown(table: dict[str, Counter], subject: str, regions: list[str]) -> str:
    """The table as markdown: trials, successes and where `subject` ended, per perturbation."""
    columns = [f"in {region}" for region in regions] + [IN_GRIPPER, ELSEWHERE, UNMOVED]
    lines = [f"| trials | n | success | {' | '.join(f'{subject} {c}' for c in columns)} |",
             "|---|" + "---|" * (len(columns) + 2)]  # fmt: skip
    for name, counts in table.items():
        label = name if name == "original" else f"Δ{name}"
        cells = " | ".join(str(counts[c]) for c in columns)
        lines.append(f"| {label} | {counts['trials']} | {counts['success']} | {cells} |")
    return "\n".join(lines) + "\n"
