"""The default policy's recipe at smoke size: a LeRobotDataset of labelled demonstrations, `lerobot-train`, a DAgger
round, the closed-loop check, shipping, and resuming without redoing finished work."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from lerobot.datasets import LeRobotDataset

from lerobot_contrast.domains.language_table.task import LanguageTableTask
from lerobot_contrast.training import targets
from lerobot_contrast.training.episodes import NoisyOracle, Simulator
from lerobot_contrast.training.recipe import REPO_ID, Recipe, run, ship


def test_demonstration_labels_are_the_noise_free_oracle_even_when_noise_is_executed():
    task = LanguageTableTask()
    instance = task.sample(1, np.random.default_rng(5))[0]
    noisy, clean = [], []
    Simulator(task).rollout(instance, NoisyOracle(0.0, np.random.default_rng(0)), 5, record=clean.append)
    Simulator(task).rollout(instance, NoisyOracle(0.05, np.random.default_rng(0)), 5, record=noisy.append)
    np.testing.assert_array_equal(noisy[0]["action"], clean[0]["action"])  # same start state, same label
    assert not np.allclose(noisy[-1]["observation.state"], clean[-1]["observation.state"])  # noise was executed
    assert set(targets.features()) <= set(noisy[0])
    assert noisy[0]["task"] == instance.instruction


class FrameList:
    """A dataset's writing calls, kept in a list of episodes."""

    def __init__(self) -> None:
        self.episodes, self.pending = [], []

    def add_frame(self, frame: dict) -> None:
        self.pending.append(frame)

    def has_pending_frames(self) -> bool:
        return bool(self.pending)

    def save_episode(self) -> None:
        self.episodes.append(self.pending)
        self.pending = []


@pytest.mark.slow
def test_dagger_rollouts_and_closed_loop_checks_in_lanes_match_one_lane():
    from lerobot_policy_tabletop_pointer import WEIGHTS

    from lerobot_contrast.training.episodes import record_episodes
    from lerobot_contrast.training.learner import Learner, Mixture, closed_loop

    task, learner = LanguageTableTask(), Learner(WEIGHTS)
    instances = task.sample(4, np.random.default_rng(3))
    recorded = {}
    for lanes in (1, 3):
        frames = FrameList()
        actor = Mixture(learner, 0.5, np.random.default_rng(7))
        outcomes = record_episodes(frames, Simulator(task), instances, actor, 8, lanes)
        recorded[lanes] = (outcomes, frames.episodes)
    (one, one_frames), (three, three_frames) = recorded[1], recorded[3]
    assert one == three and len(one_frames) == len(three_frames) > 1
    for a, b in zip(one_frames, three_frames, strict=True):
        assert [f["task"] for f in a] == [f["task"] for f in b]
        np.testing.assert_array_equal([f["observation.state"] for f in a], [f["observation.state"] for f in b])
        np.testing.assert_array_equal([f["action"] for f in a], [f["action"] for f in b])
    checks = [closed_loop(learner, Simulator(task), instances, 10, lanes) for lanes in (1, 4)]
    assert checks[0] == checks[1] and set(checks[0]) > {"success"}


@pytest.mark.slow
def test_smoke_recipe_trains_with_lerobot_and_resumes_without_redoing_work(tmp_path):
    recipe = Recipe(
        output_dir=tmp_path / "run",
        demos=6,
        steps=[6, 4],
        betas=[0.5],
        dagger_episodes=2,
        num_workers=0,
        eval_instances=3,
        eval_max_steps=20,
    )
    figures = run(recipe)
    assert set(figures) >= {"success", "train_cpu_s", "rounds", "weights_mb", "select_action_ms"}
    assert 0.0 <= figures["success"] <= 1.0 and figures["rounds"] == 1 and figures["train_cpu_s"] > 0
    progress = json.loads((recipe.output_dir / "progress.json").read_text())
    assert progress["done"] == ["demos", "train_0", "dagger_0", "train_1"]
    dataset = LeRobotDataset(REPO_ID, root=recipe.dataset)
    episodes = dataset.meta.total_episodes
    assert 6 <= episodes <= 8 and "observation.privileged.goal_xy" in dataset.features
    assert (recipe.train_dir(1) / "checkpoints" / "last" / "pretrained_model" / "model.safetensors").exists()

    again = run(recipe)  # every phase is finished: nothing is recorded or trained again
    assert LeRobotDataset(REPO_ID, root=recipe.dataset).meta.total_episodes == episodes
    assert again["success"] == figures["success"]

    ship(recipe, tmp_path / "weights")
    shipped = sorted(p.name for p in (tmp_path / "weights").iterdir())
    assert "model.safetensors" in shipped and "config.json" in shipped and "train_config.json" not in shipped
    assert json.loads((tmp_path / "weights" / "config.json").read_text())["pretrained_path"] is None


def test_a_steps_list_that_does_not_match_the_rounds_is_refused_in_one_line():
    script = Path(__file__).parents[2] / "scripts" / "train" / "train_default_policy.py"
    result = subprocess.run(
        [sys.executable, str(script), "--recipe.steps=[10,20]", "--recipe.betas=[0.5,0.0]"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert result.stderr.strip().splitlines() == [
        "error: --recipe.steps has 2 entries for 2 DAgger rounds; give one more than --recipe.betas "
        "(the first training run, then one per round)"
    ]


def test_a_failed_training_run_is_named_in_one_line_with_its_log(tmp_path):
    script = Path(__file__).parents[2] / "scripts" / "train" / "train_default_policy.py"
    args = ["--recipe.demos=2", "--recipe.steps=[2]", "--recipe.betas=[]", "--recipe.batch_size=0"]
    result = subprocess.run(
        [sys.executable, str(script), f"--recipe.output_dir={tmp_path}", *args],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 1 and "Traceback" not in result.stderr
    last = result.stderr.strip().splitlines()[-1]
    assert last == f"error: lerobot-train exited with 1 in round 0; its output is in {tmp_path / 'train_0.log'}"
