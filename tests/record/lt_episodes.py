"""Real Language-Table episodes for the observer tests: simulator frames in the robot's feature names."""

from __future__ import annotations

import math
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from lerobot_contrast.contrast.metrics import scored
from lerobot_contrast.contrast.task import perturb
from lerobot_contrast.contrast.trial import Outcome, TrialContext, TrialRecord
from lerobot_contrast.domains.language_table import LanguageTableTask
from lerobot_contrast.domains.language_table.config_language_table_sim import LanguageTableSimConfig
from lerobot_contrast.domains.language_table.language_table_sim import LanguageTableSim, episode_features
from lerobot_contrast.policies.oracle import OraclePolicy
from lerobot_contrast.record.journal import Journal
from lerobot_contrast.record.observer import EpisodeFiles
from lerobot_contrast.record.results import write_results
from lerobot_contrast.record.run_dir import write_json_atomic
from lerobot_contrast.record.summary import summarize

FEATURES = episode_features()
POSE_KEYS = LanguageTableSim.pose_keys
SETTINGS = {"task": "language_table", "strategy": "contrast", "policy": "oracle", "cost_unit": "m"}


def contexts(perturbations: tuple[str, ...] = ("LB1", "SB1"), n_bases: int = 1, seed: int = 3) -> list[TrialContext]:
    """Each base instance followed by those of `perturbations` that apply to it, numbered as trials."""
    task = LanguageTableTask(families=("block2block",))
    rng = np.random.default_rng(seed)
    out: list[TrialContext] = []
    for base in task.sample(n_bases, rng):
        variants = [(base, None)]
        for name in perturbations:
            perturbation = task.perturbations.get(name)
            instance = perturb(task, perturbation, base, rng)
            if instance is not None:
                variants.append((instance, perturbation.axis))
        for instance, axis in variants:
            out.append(
                TrialContext(
                    index=len(out),
                    instance=instance,
                    base=base,
                    current=base.scene,
                    planned_cost=0.0 if axis in (None, "L", "LB") else 0.05,
                    staging="reset" if axis is None else "in_place",
                    rng=np.random.default_rng([seed, len(out)]),
                    planned_trials=0,
                    axis=axis,
                    settings=dict(SETTINGS),
                )
            )
    for context in out:
        object.__setattr__(context, "planned_trials", len(out))
    return out


class Episodes:
    """Drives observers through oracle-controlled episodes of the simulated Language-Table robot."""

    def __init__(self) -> None:
        self.robot = LanguageTableSim(LanguageTableSimConfig())
        self.robot.connect()
        self.task = LanguageTableTask(families=("block2block",))

    def stage(self, context: TrialContext) -> dict[str, Any]:
        """Stage the trial's scene; the robot's first observation of it."""
        self.robot.stage_scene(context.instance.scene)
        return self.robot.get_observation()

    def run(self, observer: Any, context: TrialContext, steps: int = 12) -> tuple[TrialRecord, EpisodeFiles]:
        observation = self.stage(context)
        policy = OraclePolicy(self.robot.read_scene, self.task)
        policy.reset(context)
        observer.start(context, FEATURES, POSE_KEYS)
        start, path = time.perf_counter(), 0.0
        for step in range(steps):
            action = self.robot.send_action(policy.act(observation))
            observer.step(step / 10.0, observation, action)
            before = (observation["effector.x"], observation["effector.y"])
            observation = self.robot.get_observation()
            path += math.dist(before, (observation["effector.x"], observation["effector.y"]))
        scene_after = self.robot.read_scene()
        outcome = Outcome(
            success=self.task.is_achieved(context.instance, scene_after),
            steps=steps,
            path_length=path,
            scene_after=scene_after,
            duration_s=time.perf_counter() - start,
            reference_length=0.3,
        )
        record = scored(context, outcome, context.planned_cost, 0.0)
        return record, observer.end(record)


def record_run(run_dir: Path, contexts: list[TrialContext], observers: list[Any], steps: int = 8) -> list[TrialRecord]:
    """A run directory as the evaluation writes it, with every trial watched by `observers`: config, journal
    (records naming the observers' files), results table and summary."""
    run_dir.mkdir(parents=True, exist_ok=True)
    write_json_atomic(
        run_dir / "config.json", {"task": "language_table", "strategy": "contrast", "policy": {"type": "oracle"}}
    )
    journal = Journal.open(run_dir / "journal.jsonl")
    episodes = Episodes()
    for context in contexts:
        record, files = episodes.run(Fanout(observers), context, steps)
        journal.append(replace(record, rerun_path=files.rerun_path, dataset_episode=files.dataset_episode))
    for observer in observers:
        observer.close()
    write_results(run_dir / "results.parquet", journal.records, {"strategy": "contrast"})
    summary = summarize(journal.records, settings=dict(SETTINGS), complete=True)
    write_json_atomic(run_dir / "summary.json", summary)
    return journal.records


class Fanout:
    """Several observers as one, merging the files they report (as a runner with several observers does)."""

    def __init__(self, observers: list[Any]) -> None:
        self.observers = observers

    def start(self, *args: Any) -> None:
        for observer in self.observers:
            observer.start(*args)

    def step(self, *args: Any) -> None:
        for observer in self.observers:
            observer.step(*args)

    def end(self, record: TrialRecord) -> EpisodeFiles:
        files = [observer.end(record) for observer in self.observers]
        return EpisodeFiles(
            rerun_path=next((f.rerun_path for f in files if f.rerun_path), None),
            dataset_episode=next((f.dataset_episode for f in files if f.dataset_episode is not None), None),
        )
