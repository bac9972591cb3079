"""Planning task-file evaluations: the plan an operator follows with its costs, from Python and from the CLI."""

from __future__ import annotations

import re
import subprocess
import sys

import numpy as np
import pytest

from lerobot_contrast import Evaluation, preview
from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.contrast.staging import staging_moves
from lerobot_contrast.contrast.strategy import make_plan
from lerobot_contrast.domains import load_task
from lerobot_contrast.domains.task_file import example_names, examples_dir, load_task_file
from tests.domains.task_file.task_file_fixtures import CUPS, LISTED, write

EXAMPLES = ("so101_blocks", "so101_red_left", "lekiwi_fetch")


def dry_run(task, strategy: str, n: int, cost: str, budget: float | None = None, seed: int = 0):
    rng = np.random.default_rng(seed)
    perturbations = list(task.perturbations) if strategy == "contrast" else []
    plan = make_plan(strategy, task.sample(n, rng), perturbations, 1, rng)
    return plan, preview(Evaluation(task, plan, task.cost_model(cost), budget, seed))


@pytest.mark.parametrize("example", EXAMPLES)
def test_the_contrast_plan_restages_in_place_and_charges_only_scene_changes(example):
    task = load_task(example)
    plan, records = dry_run(task, "contrast", 4, "distance")
    assert len(records) == len(plan) == 4 * (1 + len(task.perturbations))
    first = records[0]
    assert first.staging == "reset" and {
        m.name for m in staging_moves(task.storage_scene(), first.instance.scene)
    } >= set(task.spec.placed)
    scene = task.storage_scene()
    for record in records:
        if record.status == "not_applicable":
            assert record.cost == 0.0 and record.instance is None
            continue
        moves = staging_moves(scene, record.instance.scene, task.spec.cost.tolerance)
        assert (record.cost > 0) == bool(moves)
        if record.axis in ("L", "LB"):
            assert record.cost == 0.0 and record.staging == "in_place"
        if record.axis in ("S", "SB"):
            assert record.cost > 0 and len(moves) == 1
        scene = record.scene_after
    assert records[-1].cumulative_cost == pytest.approx(sum(r.cost for r in records))


@pytest.mark.parametrize("example", EXAMPLES)
def test_the_budget_stops_the_plan_after_the_trial_that_crosses_it(example):
    task = load_task(example)
    _, unlimited = dry_run(task, "standard", 10, "reset_time")
    budget = unlimited[4].cumulative_cost - 1.0
    _, records = dry_run(task, "standard", 10, "reset_time", budget=budget)
    assert len(records) == 5 and records[-1].cumulative_cost > budget >= records[-2].cumulative_cost


def test_the_cost_models_use_the_files_tolerance_add_remove_and_handling_times():
    so101 = load_task("so101_blocks")
    scene = so101.sample(1, np.random.default_rng(0))[0].scene
    red = scene.objects["red_cube"]
    distance = so101.cost_model("distance")
    assert distance(scene, scene.with_object("red_cube", Pose(red.x + 0.1, red.y))) == pytest.approx(0.1)
    assert distance(scene, scene.with_object("red_cube", Pose(red.x + 0.004, red.y))) == 0.0  # tolerance 0.5 cm
    assert distance(scene, scene.with_object("yellow_cube", Pose(0.3, 0.0))) == pytest.approx(0.21)  # add_remove
    lekiwi = load_task("lekiwi_fetch")
    room = lekiwi.sample(1, np.random.default_rng(0))[0].scene
    box, cup = room.objects["cardboard_box"], room.objects["red_cup"]
    reset = lekiwi.cost_model("reset_time")
    assert (reset.name, reset.unit) == ("reset_time", "s")
    assert reset(room, room.with_object("cardboard_box", Pose(box.x + 1.2, box.y))) == pytest.approx(8 + 1.2 / 0.6)
    assert reset(room, room.with_object("red_cup", Pose(cup.x, cup.y + 0.6))) == pytest.approx(4 + 0.6 / 0.6)


def test_a_listed_evaluation_set_is_planned_as_listed(tmp_path):
    task = load_task_file(write(tmp_path, CUPS + LISTED))
    plan, records = dry_run(task, "standard", 2, "distance", seed=1)
    assert sorted(r.instance.instruction for r in records) == [
        "move the red cup to the left",
        "put the blue cup on the right",
    ]
    assert {r.family for r in records} == {"move", "by_hand"}


def test_the_examples_ship_with_the_package_and_load_by_name_and_by_path():
    assert set(EXAMPLES) <= set(example_names())
    for name in EXAMPLES:
        by_path = load_task(str(examples_dir() / f"{name}.yaml"))
        assert by_path.name == load_task(name).name == name


def test_the_dry_run_prints_the_plan_with_moves_and_planned_cost():
    result = subprocess.run(
        [sys.executable, "-m", "lerobot_contrast.eval", "--task=so101_blocks", "--dry_run=true"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    out = result.stdout
    assert out.startswith("[   1] original  so101_blocks-0000  stage=reset")
    assert re.search(r"move (red|green|blue)_cube +\(\+0\.\d{3}, \+0\.\d{3}\) -> \([+-]0\.\d{3}, [+-]0\.\d{3}\)", out)
    assert "ΔLB2" in out and "ΔSB" in out
    assert re.search(r"plan: \d+ trials \(\d+ not applicable\) of 400 planned, planned cost \d+\.\d\d m", out)
