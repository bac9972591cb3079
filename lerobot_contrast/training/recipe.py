"""The default policy's recipe: oracle demonstrations, `lerobot-train`, then DAgger rounds, all resumable.

Every phase leaves its result in `output_dir` and is skipped when it is already there, so a killed run started
again with the same settings goes on where it stopped (an unfinished `lerobot-train` run resumes from its last
checkpoint through LeRobot's own `--resume`).
"""

from __future__ import annotations

import json
import os
import resource
import shutil
import subprocess
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from lerobot_contrast.domains.language_table import board
from lerobot_contrast.domains.language_table.task import LanguageTableTask
from lerobot_contrast.record.third_party import third_party_output
from lerobot_contrast.training.episodes import NoisyOracle, Simulator, open_dataset, record_episodes
from lerobot_contrast.training.learner import LANES, Learner, Mixture, closed_loop

REPO_ID = "local/tabletop_pointer_demos"


@dataclass
class Recipe:
    output_dir: Path = Path("outputs/default_policy")
    seed: int = 0
    # Oracle demonstrations, executed with this much action noise (labels stay noise-free).
    demos: int = 1500
    demo_noise: float = 0.01
    # Gradient steps of each training run: the first from scratch, then one after each DAgger round.
    steps: list[int] = field(default_factory=lambda: [5000, 1500, 1500, 1500, 2000, 3000, 2000])
    batch_size: int = 32
    num_workers: int = 1
    # Torch threads of each training run: on a shared 2-core CPU one thread per process beats contending ones.
    train_threads: int = 1
    # DAgger: learner roll-outs per round, and the oracle's share of executed actions in each round.
    betas: list[float] = field(default_factory=lambda: [0.5, 0.2, 0.0, 0.0, 0.0, 0.0])
    dagger_episodes: int = 250
    max_steps: int = 120
    # Closed-loop check after training: fresh instances from a seed never used for data.
    eval_instances: int = 250
    eval_seed: int = 1_000_003
    eval_max_steps: int = board.MAX_EPISODE_STEPS
    device: str = "cpu"
    # DAgger roll-outs and the closed-loop check run this many episodes side by side, with the results of one.
    lanes: int = LANES
    # lerobot-train saves a checkpoint this often (steps), so a killed run loses at most this many.
    save_every: int = 1000

    def __post_init__(self) -> None:
        if len(self.steps) != len(self.betas) + 1:
            raise ValueError(
                f"--recipe.steps has {len(self.steps)} entries for {len(self.betas)} DAgger rounds; "
                "give one more than --recipe.betas (the first training run, then one per round)"
            )

    @property
    def dataset(self) -> Path:
        return self.output_dir / "dataset"

    def training_data(self, round_index: int) -> Path:
        """What training round `round_index` reads (one dataset the rounds append to)."""
        return self.dataset

    def train_dir(self, round_index: int) -> Path:
        return self.output_dir / f"train_{round_index}"

    def final_model(self) -> Path:
        return self.train_dir(len(self.betas)) / "checkpoints" / "last" / "pretrained_model"


class RecipeError(RuntimeError):
    """A phase that failed; the message names it and where its output is."""


class Progress:
    """`progress.json`: finished phases and the CPU seconds spent, kept across restarts."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.state = json.loads(path.read_text()) if path.exists() else {"done": [], "cpu_s": 0.0}
        self._mark = _cpu_seconds()

    def done(self, phase: str) -> bool:
        return phase in self.state["done"]

    def finish(self, phase: str) -> None:
        now = _cpu_seconds()
        self.state["cpu_s"] += now - self._mark
        self._mark = now
        self.state["done"].append(phase)
        tmp = self.path.with_suffix(".tmp")
        tmp.write_text(json.dumps(self.state, indent=1))
        os.replace(tmp, self.path)


def _cpu_seconds() -> float:
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def _record(recipe: Recipe, actor, instances, label: str) -> None:
    dataset = open_dataset(recipe.dataset, REPO_ID)
    simulator = Simulator(LanguageTableTask())
    start = time.time()
    outcomes = record_episodes(dataset, simulator, instances, actor, recipe.max_steps, recipe.lanes)
    dataset.finalize()
    wins = sum(o.success for o in outcomes)
    print(
        f"[{label}] {len(outcomes)} episodes, {sum(o.steps for o in outcomes)} frames, "
        f"success {wins / max(1, len(outcomes)):.2f}, {time.time() - start:.0f} s",
        flush=True,
    )


def lerobot_train(recipe: Any, round_index: int, policy_type: str, repo_id: str) -> None:
    """One training run of a recipe (this one or the navigator's) through `lerobot-train`: from scratch in round 0,
    else from the previous round's model; resumed from its last checkpoint when one is there."""
    out = recipe.train_dir(round_index)
    steps = recipe.steps[round_index]
    if (out / "checkpoints").exists():
        args = ["--resume=true", f"--config_path={_last_model(recipe, round_index) / 'train_config.json'}"]
    else:
        shutil.rmtree(out, ignore_errors=True)  # lerobot-train refuses an existing output dir without a checkpoint
        previous = _last_model(recipe, round_index - 1)
        policy = [f"--policy.type={policy_type}"] if round_index == 0 else [f"--policy.path={previous}"]
        args = [
            f"--dataset.repo_id={repo_id}",
            f"--dataset.root={recipe.training_data(round_index)}",
            *policy,
            "--policy.push_to_hub=false",
            f"--policy.device={recipe.device}",
            f"--steps={steps}",
            f"--batch_size={recipe.batch_size}",
            f"--save_freq={max(1, min(recipe.save_every, steps))}",
            f"--num_workers={recipe.num_workers}",
            f"--seed={recipe.seed + round_index}",
            f"--output_dir={out}",
            "--log_freq=100",
            "--wandb.enable=false",
        ]
    command = [str(Path(sys.executable).parent / "lerobot-train"), *args]
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "OMP_NUM_THREADS": str(recipe.train_threads)}
    log_path = recipe.output_dir / f"train_{round_index}.log"
    with open(log_path, "a") as log:
        status = subprocess.run(command, stdout=log, stderr=subprocess.STDOUT, env=env).returncode
    if status != 0:
        raise RecipeError(f"lerobot-train exited with {status} in round {round_index}; its output is in {log_path}")


def _last_model(recipe: Any, round_index: int) -> Path:
    return recipe.train_dir(round_index) / "checkpoints" / "last" / "pretrained_model"


def run(recipe: Recipe) -> dict[str, float]:
    """All phases (skipping finished ones), then the closed-loop check of the final policy."""
    import torch

    # One thread: this process renders and runs small tensors, where more threads only contend.
    torch.set_num_threads(1)
    recipe.output_dir.mkdir(parents=True, exist_ok=True)
    (recipe.output_dir / "recipe.json").write_text(json.dumps(asdict(recipe), indent=1, default=str))
    with third_party_output(recipe.output_dir):  # LeRobot's warnings once, in one line; in full in the log
        return _phases(recipe)


def _phases(recipe: Recipe) -> dict[str, float]:
    progress = Progress(recipe.output_dir / "progress.json")
    task = LanguageTableTask()
    if not progress.done("demos"):
        rng = np.random.default_rng(recipe.seed)
        instances = task.sample(recipe.demos, rng)
        _record(recipe, NoisyOracle(recipe.demo_noise, rng), instances, "demos")
        progress.finish("demos")
    for round_index in range(len(recipe.betas) + 1):
        if not progress.done(f"train_{round_index}"):
            lerobot_train(recipe, round_index, "tabletop_pointer", REPO_ID)
            progress.finish(f"train_{round_index}")
        if round_index < len(recipe.betas) and not progress.done(f"dagger_{round_index}"):
            rng = np.random.default_rng([recipe.seed, round_index + 1])
            learner = Learner(recipe.train_dir(round_index) / "checkpoints" / "last" / "pretrained_model")
            instances = task.sample(recipe.dagger_episodes, rng)
            _record(recipe, Mixture(learner, recipe.betas[round_index], rng), instances, f"dagger {round_index}")
            progress.finish(f"dagger_{round_index}")
    return evaluate(recipe, progress)


def evaluate(recipe: Recipe, progress: Progress) -> dict[str, float]:
    learner = Learner(recipe.final_model())
    instances = LanguageTableTask().sample(recipe.eval_instances, np.random.default_rng(recipe.eval_seed))
    figures = closed_loop(learner, Simulator(LanguageTableTask()), instances, recipe.eval_max_steps, recipe.lanes)
    figures["train_cpu_s"] = progress.state["cpu_s"]
    figures["rounds"] = len(recipe.betas)
    figures["weights_mb"] = sum(p.stat().st_size for p in _shipped_files(recipe.final_model())) / 1e6
    figures["select_action_ms"] = select_action_ms(learner, instances[0])
    return figures


def select_action_ms(learner: Learner, instance) -> float:
    """Median wall time of one `select_action` on one CPU thread, on a full-size camera frame."""
    import torch

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        simulator = Simulator(LanguageTableTask())
        robot = instance.scene.robot
        simulator.physics.set_state(
            {n: (p.x, p.y, p.yaw) for n, p in instance.scene.objects.items()}, (robot.x, robot.y)
        )
        batch = learner.batch([simulator.observation()], [instance.instruction])
        learner.policy.reset()
        times = []
        for _ in range(50):
            start = time.perf_counter()
            learner.policy.select_action(batch)
            times.append(time.perf_counter() - start)
        return float(np.median(times) * 1000)
    finally:
        torch.set_num_threads(threads)


def ship(recipe: Recipe, weights_dir: Path) -> None:
    """Copy the final policy's files (no training state) into the plugin's shipped `weights/` directory."""
    weights_dir.mkdir(parents=True, exist_ok=True)
    for path in _shipped_files(recipe.final_model()):
        shutil.copy2(path, weights_dir / path.name)
    # The checkpoint it was fine-tuned from exists only on the training machine.
    config = json.loads((weights_dir / "config.json").read_text())
    config["pretrained_path"] = None
    (weights_dir / "config.json").write_text(json.dumps(config, indent=4) + "\n")


def _shipped_files(model_dir: Path) -> list[Path]:
    return sorted(p for p in model_dir.iterdir() if p.name != "train_config.json")
