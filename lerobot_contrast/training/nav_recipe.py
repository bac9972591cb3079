"""The `vln_navigator` recipe: teacher demonstrations, `lerobot-train`, then DAgger rounds, all resumable.

Every phase leaves its result in `output_dir` and is skipped when it is already there, so a killed run started
again with the same settings goes on where it stopped: `lerobot-train` resumes from its last checkpoint, and each
recording phase writes a dataset of its own, so one killed mid-way is recorded again from its start without
touching the finished ones (training round k reads the demonstrations and rounds 0..k-1 aggregated).
Demonstrations and DAgger roll-outs use training-split arrangements; the closed-loop check uses evaluation-split
ones from a seed never used for training (`sampler`).
"""

from __future__ import annotations

import json
import shutil
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from lerobot_contrast.domains.vln.sampler import MAX_INSTANCES, sample_arrangements
from lerobot_contrast.domains.vln.task import SUCCESS_RADIUS_M
from lerobot_contrast.record.third_party import third_party_output
from lerobot_contrast.training.episodes import record_episodes
from lerobot_contrast.training.nav_episodes import NavSimulator, SlippingTeacher, open_dataset
from lerobot_contrast.training.nav_learner import NavLearner, NavMixture, closed_loop, select_action_ms
from lerobot_contrast.training.recipe import Progress, _shipped_files, lerobot_train

REPO_ID = "local/vln_navigator_demos"


@dataclass
class NavRecipe:
    output_dir: Path = Path("outputs/nav_policy")
    seed: int = 0
    # Teacher demonstrations on training arrangements; the executed command slips to a random move at this rate.
    demos: int = 200
    slip: float = 0.15
    # Gradient steps of each training run: the first from scratch, then one after each DAgger round.
    steps: list[int] = field(default_factory=lambda: [2500, 1500])
    batch_size: int = 32
    num_workers: int = 0
    train_threads: int = 1
    # DAgger: learner roll-outs per round, and the teacher's share of executed commands in each round.
    betas: list[float] = field(default_factory=lambda: [0.3])
    dagger_episodes: int = 60
    max_steps: int = 120
    # Closed-loop check after training: fresh evaluation-split arrangements.
    eval_instances: int = 250
    eval_seed: int = 1_000_003
    device: str = "cpu"
    # lerobot-train saves a checkpoint this often (steps), so a killed run loses at most this many.
    save_every: int = 250

    def __post_init__(self) -> None:
        if len(self.steps) != len(self.betas) + 1:
            raise ValueError(
                f"--recipe.steps has {len(self.steps)} entries for {len(self.betas)} DAgger rounds; "
                "give one more than --recipe.betas (the first training run, then one per round)"
            )
        for name in ("demos", "dagger_episodes", "eval_instances"):
            if not 1 <= getattr(self, name) <= MAX_INSTANCES:
                raise ValueError(
                    f"--recipe.{name} must be 1 to {MAX_INSTANCES} arrangements, got {getattr(self, name)}"
                )
        if min(self.steps) < 1 or self.save_every < 1 or self.batch_size < 1:
            raise ValueError("--recipe.steps, --recipe.batch_size and --recipe.save_every must be at least 1")
        if any(not 0.0 <= beta <= 1.0 for beta in self.betas) or not 0.0 <= self.slip <= 1.0:
            raise ValueError(
                f"--recipe.betas and --recipe.slip are probabilities in [0, 1], got {self.betas}, {self.slip}"
            )

    def recorded(self, phase: str) -> Path:
        """The dataset a recording phase (`demos`, `dagger_0`, ...) writes."""
        return self.output_dir / "datasets" / phase

    def training_data(self, round_index: int) -> Path:
        """What training round `round_index` reads: the demonstrations, then with every earlier round's roll-outs."""
        if round_index == 0:
            return self.recorded("demos")
        return self.output_dir / "datasets" / f"train_{round_index}"

    def train_dir(self, round_index: int) -> Path:
        return self.output_dir / f"train_{round_index}"

    def model(self, round_index: int) -> Path:
        return self.train_dir(round_index) / "checkpoints" / "last" / "pretrained_model"

    def final_model(self) -> Path:
        return self.model(len(self.betas))


def _record(recipe: NavRecipe, actor, instances, label: str, phase: str) -> None:
    root = recipe.recorded(phase)
    shutil.rmtree(root, ignore_errors=True)  # what a killed run left of this unfinished phase
    dataset = open_dataset(root, REPO_ID)
    start = time.time()
    outcomes = record_episodes(dataset, NavSimulator(), instances, actor, recipe.max_steps)
    dataset.finalize()
    wins = sum(o.success for o in outcomes)
    print(
        f"[{label}] {len(outcomes)} episodes, {sum(o.steps for o in outcomes)} frames, "
        f"success {wins / max(1, len(outcomes)):.2f}, {time.time() - start:.0f} s",
        flush=True,
    )


def run(recipe: NavRecipe) -> dict[str, float]:
    """All phases (skipping finished ones), then the closed-loop check of the final policy."""
    import torch

    torch.set_num_threads(1)  # this process renders and runs small tensors, where more threads only contend
    recipe.output_dir.mkdir(parents=True, exist_ok=True)
    (recipe.output_dir / "recipe.json").write_text(json.dumps(asdict(recipe), indent=1, default=str))
    with third_party_output(recipe.output_dir):
        return _phases(recipe)


def _phases(recipe: NavRecipe) -> dict[str, float]:
    progress = Progress(recipe.output_dir / "progress.json")
    if not progress.done("demos"):
        rng = np.random.default_rng(recipe.seed)
        instances = sample_arrangements(recipe.demos, "train", recipe.seed, SUCCESS_RADIUS_M)
        _record(recipe, SlippingTeacher(recipe.slip, rng), instances, "demos", "demos")
        progress.finish("demos")
    for round_index in range(len(recipe.betas) + 1):
        if not progress.done(f"train_{round_index}"):
            if round_index > 0 and not (recipe.train_dir(round_index) / "checkpoints").exists():
                _aggregate(recipe, round_index)
            lerobot_train(recipe, round_index, "vln_navigator", REPO_ID)
            progress.finish(f"train_{round_index}")
        if round_index < len(recipe.betas) and not progress.done(f"dagger_{round_index}"):
            rng = np.random.default_rng([recipe.seed, round_index + 1])
            base = recipe.seed * 1000 + round_index + 1  # a training stream of its own for each round
            instances = sample_arrangements(recipe.dagger_episodes, "train", base, SUCCESS_RADIUS_M)
            learner = NavLearner(recipe.model(round_index))
            mixture = NavMixture(learner, recipe.betas[round_index], rng)
            _record(recipe, mixture, instances, f"dagger {round_index}", f"dagger_{round_index}")
            progress.finish(f"dagger_{round_index}")
    return evaluate(recipe, progress)


def _aggregate(recipe: NavRecipe, round_index: int) -> None:
    """Round `round_index`'s training set: the demonstrations and rounds 0..round_index-1, built afresh."""
    from lerobot.datasets.aggregate import aggregate_datasets

    phases = ["demos", *(f"dagger_{k}" for k in range(round_index))]
    target = recipe.training_data(round_index)
    shutil.rmtree(target, ignore_errors=True)
    roots = [recipe.recorded(phase) for phase in phases]
    aggregate_datasets([REPO_ID] * len(roots), REPO_ID, roots=roots, aggr_root=target)


def evaluate(recipe: NavRecipe, progress: Progress, model: Path | None = None) -> dict[str, float]:
    learner = NavLearner(model or recipe.final_model())
    instances = sample_arrangements(recipe.eval_instances, "eval", recipe.eval_seed, SUCCESS_RADIUS_M)
    figures = closed_loop(learner, NavSimulator(), instances, recipe.max_steps)
    figures["train_cpu_s"] = progress.state["cpu_s"]
    figures["rounds"] = len(recipe.betas)
    figures["weights_mb"] = sum(p.stat().st_size for p in _shipped_files(model or recipe.final_model())) / 1e6
    figures["select_action_ms"] = select_action_ms(learner, instances[0])
    return figures
