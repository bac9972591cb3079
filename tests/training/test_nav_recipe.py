"""The navigator's recipe: each recording phase is a dataset of its own that a restart records again from scratch
when a kill left it half-written, later rounds train on the phases aggregated, bad settings are one line, and the
whole recipe runs through `lerobot-train` and resumes without redoing finished work."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from lerobot.datasets import LeRobotDataset

from lerobot_contrast.domains.vln.sampler import sample_arrangements
from lerobot_contrast.domains.vln.task import SUCCESS_RADIUS_M
from lerobot_contrast.training.nav_episodes import SlippingTeacher
from lerobot_contrast.training.nav_recipe import REPO_ID, NavRecipe, _aggregate, _record, run

SCRIPT = Path(__file__).parents[2] / "scripts" / "train" / "train_nav_policy.py"


def episodes(root: Path) -> int:
    return LeRobotDataset(REPO_ID, root=root).meta.total_episodes


def record(recipe: NavRecipe, phase: str, n: int) -> None:
    instances = sample_arrangements(n, "train", 5, SUCCESS_RADIUS_M)
    _record(recipe, SlippingTeacher(0.0, np.random.default_rng(0)), instances, phase, phase)


@pytest.mark.slow
def test_a_recording_phase_a_kill_left_half_written_is_recorded_again_from_its_start(tmp_path):
    recipe = NavRecipe(output_dir=tmp_path, max_steps=4)
    record(recipe, "demos", 2)
    record(recipe, "dagger_0", 1)
    # What a kill during the next round's recording leaves: metadata and a truncated parquet file.
    broken = recipe.recorded("dagger_1")
    (broken / "data" / "chunk-000").mkdir(parents=True)
    (broken / "meta").mkdir()
    (broken / "data" / "chunk-000" / "file-000.parquet").write_bytes(b"PAR1 truncated")
    (broken / "meta" / "info.json").write_text((recipe.recorded("demos") / "meta" / "info.json").read_text())
    record(recipe, "dagger_1", 1)
    assert [episodes(recipe.recorded(p)) for p in ("demos", "dagger_0", "dagger_1")] == [2, 1, 1]

    _aggregate(recipe, 2)
    _aggregate(recipe, 2)  # rebuilt, not appended to, when a restart builds it again
    assert episodes(recipe.training_data(2)) == 4  # the demonstrations and rounds 0 and 1
    assert recipe.training_data(0) == recipe.recorded("demos")


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (["--recipe.steps=[10,20]"], "--recipe.steps has 2 entries for 0 DAgger rounds"),
        (["--recipe.demos=0"], "--recipe.demos must be 1 to 5000 arrangements, got 0"),
        (["--recipe.betas=[1.5]", "--recipe.steps=[1,1]"], "--recipe.betas and --recipe.slip are probabilities"),
    ],
)
def test_bad_settings_are_refused_in_one_line(flags, message):
    result = subprocess.run(
        [sys.executable, str(SCRIPT), "--recipe.betas=[]", "--recipe.steps=[1]", *flags],
        capture_output=True,
        text=True,
        timeout=120,
    )
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1 and message in lines[0], result.stderr


@pytest.mark.slow
def test_the_recipe_trains_with_lerobot_runs_a_dagger_round_and_resumes_without_redoing_work(tmp_path):
    recipe = NavRecipe(
        output_dir=tmp_path / "run",
        demos=2,
        steps=[4, 2],
        betas=[0.5],
        dagger_episodes=1,
        eval_instances=2,
        max_steps=8,
        save_every=2,
    )
    figures = run(recipe)
    assert {"success", "progress", "spl", "train_cpu_s", "rounds", "weights_mb", "select_action_ms"} <= set(figures)
    assert figures["rounds"] == 1 and 0.0 <= figures["progress"] <= 1.0 and figures["weights_mb"] < 20
    progress = json.loads((recipe.output_dir / "progress.json").read_text())
    assert progress["done"] == ["demos", "train_0", "dagger_0", "train_1"]
    assert episodes(recipe.training_data(1)) == episodes(recipe.recorded("demos")) + 1
    checkpoints = sorted(p.name for p in (recipe.train_dir(0) / "checkpoints").iterdir())
    assert checkpoints == ["000002", "000004", "last"]  # a kill loses at most save_every steps

    again = run(recipe)  # every phase is finished: nothing is recorded or trained again
    assert json.loads((recipe.output_dir / "progress.json").read_text()) == progress
    assert again["progress"] == figures["progress"]
