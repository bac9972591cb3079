"""The "Write your own task" example (a task file and the Python API in a few lines) runs as written.

MY_TABLE and EXAMPLE are the README's two code blocks for that section."""

from __future__ import annotations

import subprocess
import sys

MY_TABLE = """\
# An SO-101 putting mugs on a tray or a shelf (lengths in centimetres, the arm's base at the origin).
version: 1
name: my_table
description: mugs on a tray or a shelf
workspace:
  units: cm
  bounds: {x: [15, 45], y: [-25, 25]}
  min_spacing: 8
  robot_start: [20, 0]
  regions:
    tray: {center: [35, 15], radius: 7, words: [tray, serving tray]}
    shelf: {center: [35, -15], radius: 7}
    table: {x: [18, 42], y: [-8, 8]}
objects:
  red_mug: {colour: red, category: mug, area: table}
  blue_mug: {colour: blue, category: mug, area: table}
  green_mug: {colour: green, category: mug, area: table, spare: true}
templates:
  - name: put
    text: ["put the {mug} on the {place}", "move the {mug} onto the {place}"]
    slots: {mug: {category: mug}, place: [tray, shelf]}
    goal: {subject: "{mug}", in: "{place}"}
outcome: {mode: predicate, reference: straight_line}
perturbations:
  - {name: L, kind: paraphrase, synonyms: [[put, place], [move, slide]]}
  - {name: LB, kind: flip, pairs: [[tray, shelf]]}
  - {name: S, kind: add_remove_distractor}
  - {name: SB, kind: move_goal_object, min_move: 10}
cost: {add_remove: 30, handling_time_s: {default: 3}}
"""

EXAMPLE = """\
import numpy as np

from lerobot_contrast.contrast import Outcome, Pose, make_plan, perturb
from lerobot_contrast.evaluate import LoopState, run_trials
from lerobot_contrast.record.summary import format_summary, summarize
from lerobot_contrast.tasks.task_file import load_task

task = load_task("my_table.yaml")  # or a shipped example by name: load_task("so101_blocks")
rng = np.random.default_rng(0)
instances = task.sample(6, rng)  # the i.i.d. evaluation set
flipped = perturb(task, task.perturbations.get("LB"), instances[0], rng)  # one contrast instance, by hand
print(instances[0].instruction, "->", flipped.instruction)


def robot(trial):  # a stand-in that does as it is told; replace it with your robot running your policy
    goal = trial.instance.goal["predicate"]
    x, y = task.spec.workspace.regions[goal["in"]].middle
    after = trial.instance.scene.with_object(goal["subject"], Pose(x, y))
    success, reference = task.is_achieved(trial.instance, after), task.reference_length(trial.instance)
    return Outcome(success, steps=50, path_length=0.4, scene_after=after, duration_s=15.0, reference_length=reference)


plan = make_plan("contrast", instances, list(task.perturbations), repeats=1, rng=rng)
cost = task.cost_model("distance")  # or "reset_time", with the file's handling times
records = run_trials(plan, task, cost, budget=3.0, seed=0, state=LoopState(task.storage_scene()), execute=robot)
print(format_summary(summarize(records, settings={}, complete=True), cost.unit))
"""


def test_the_task_file_example_loads_perturbs_plans_evaluates_and_reports(tmp_path):
    (tmp_path / "my_table.yaml").write_text(MY_TABLE, encoding="utf-8")
    (tmp_path / "example.py").write_text(EXAMPLE, encoding="utf-8")
    result = subprocess.run([sys.executable, "example.py"], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    first, *table = result.stdout.strip().splitlines()
    before, after = first.split(" -> ")
    assert before != after and before.replace("shelf", "tray") == after.replace("shelf", "tray")
    rows = {line.split()[0]: line.split() for line in table[2:] if not line.startswith("-")}
    assert set(rows) == {"original", "ΔL", "ΔLB", "ΔS", "ΔSB", "all"}
    assert float(rows["ΔL"][-1]) == float(rows["ΔLB"][-1]) == 0.0  # wording costs nothing to stage
    assert float(rows["all"][-1]) > 3.0 and float(rows["ΔS"][-1]) > 0.0  # stops just past the 3 m budget
