"""The `python -m lerobot_contrast.eval` configuration (draccus; the comment above each field is its --help)."""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import draccus

from lerobot_contrast.operators.arm.args import ArmArgs
from lerobot_contrast.operators.person_args import PersonArgs
from lerobot_contrast.policies.base import PolicyArgs
from lerobot_contrast.spine.flags import ConfigError as ConfigError  # where the commands catch it
from lerobot_contrast.staging.args import StagingArgs


class _LazyModule:
    """A module imported when an attribute is first read. LeRobot's robots load torch (seconds): draccus reads the
    robot field's type only when it parses, so flag names are checked before that (eval's main)."""

    def __init__(self, name: str) -> None:
        self._name = name

    def __getattr__(self, attribute: str) -> Any:
        return getattr(importlib.import_module(self._name), attribute)


if TYPE_CHECKING:
    from lerobot import robots
else:
    robots = _LazyModule("lerobot.robots")


@dataclass
class StopArgs:
    """Sequential stopping rules, checked after every trial (anytime-valid: stopping early keeps their level)."""

    # Stop once the anytime-valid interval of the headline metric (SPL, else progress) is at most this wide.
    width: float | None = None
    # Stop once this run's paired difference from a finished run of the same plan is decided:
    # a run directory or hub:USER/NAME (run with its --plan).
    compare: str | None = None
    # 1 - confidence of the anytime-valid intervals and of the comparison (with --policies: family-wise, over pairs).
    alpha: float = 0.05
    # With --policies: end the session once every pair of policies is decided.
    decided: bool = False


@dataclass
class EvalConfig:
    """Contrast-set evaluation of a language-guided policy."""

    # The task: a built-in domain (language_table), a shipped task file by name (so101_blocks, lekiwi_fetch),
    # or the path of a task .yaml file.
    task: str = "language_table"
    # Task families to sample from (default: all of the task's families), e.g. block2block,separate
    # (or [block2block,separate]).
    families: list[str] | None = None
    # standard (i.i.d., full reset each trial), contrast (the paper's Algorithm 1) or limited_intervention
    # (new instructions, reset when infeasible).
    strategy: str = "contrast"
    # Perturbations the contrast strategy applies after each base instance, in order (default: all of the
    # task's), e.g. LB1,LB2,SB1,SB2.
    perturbations: list[str] | None = None
    # Order in which base instances are visited: iid (as sampled), cost_aware (same bases, cheaper to stage), or
    # adaptive (bases as sampled; after each trial, the perturbation with most information per staging cost).
    order: str = "iid"
    # Number of i.i.d. base instances in the evaluation set (default: the task's own, 50 for Language-Table,
    # the 5 shipped arrangements for VLN).
    n_instances: int | None = None
    # Times each planned trial is run (restaging the same scene between repeats).
    repeats: int = 1
    # Experimenter-cost budget K in the cost model's unit; the run stops once the cumulative cost exceeds
    # it (default: no limit).
    budget: float | None = None
    # Cost model: distance (metres moved), reset_time (seconds of restaging), measured (metres a calibrated camera
    # saw moved), robot_time or interventions (--operator=arm: the arm's seconds, a person's calls).
    cost: str = "distance"
    # Seed of every random choice: the same seed gives the same plan and, in simulation, the same results.
    seed: int = 0
    # Episode length limit in control steps (10 Hz for Language-Table).
    max_episode_steps: int = 200
    # Episode length limit in seconds (default: none besides --max_episode_steps).
    max_episode_s: float | None = None
    # The policy under evaluation.
    policy: PolicyArgs = field(default_factory=PolicyArgs)
    # Compare policies interleaved, each trial run by every one in turn from the same staged scene (docs: ab.md):
    # A,B[,C], each a policy type, directory or repo id, with its own options, e.g. tabletop_pointer:noise_std=0.02.
    policies: str | None = None
    # With --policies: the operator's console names the running policy only once its trial is labelled.
    blind: bool = False
    # The robot: any LeRobot robot type, plugins included (e.g. so101_follower, lekiwi_client, locobot), or
    # by default the task's simulator: language_table_sim (--task=language_table) or vln_sim (--task=vln).
    robot: robots.RobotConfig | None = None
    # Control rate in Hz; default: 10 on hardware, as fast as possible on a simulated robot.
    fps: float | None = None
    # wall (real time), or the twin's simulated clock: tcp://HOST:PORT, in its eval flags.
    clock: str = "wall"
    # Who stages and labels: console (a person), arm (the SO-101 and its camera; unattended.md) or auto (the robot
    # stages its own scene). Default: auto where it can, else console.
    operator: str | None = None
    # With --operator=console: each prompt also as a JSON line to this file, FIFO or /dev/fd/N, for a program.
    operator_channel: str | None = None
    # Map robot observation keys to the policy's input features, e.g. {"observation.images.top": "observation.images.front"}.
    rename_map: dict[str, str] = field(default_factory=dict)
    # Re-run a published or local evaluation's plan (its task, instances, perturbations, order and budget)
    # against this policy: hub:USER/NAME or a run directory.
    plan: str | None = None
    # Record every episode to rerun/episode_NNNNNN.rrd in the run directory.
    rerun: bool = True
    # Record every episode into a LeRobotDataset v3 in the run directory (dataset/).
    record_dataset: bool = False
    # Publish the run directory to the Hugging Face Hub as a dataset repo when the run ends (needs --repo_id).
    push_to_hub: bool = False
    # The Hub dataset repo to publish to, USER/NAME.
    repo_id: str | None = None
    # Create the Hub repo private.
    private: bool = False
    # Run directory (default: outputs/contrast/<date>/<time>_<task>_<strategy>).
    output_dir: Path | None = None
    # Continue the run in --output_dir where it stopped.
    resume: bool = False
    # With --resume: run again the trials a lost robot aborted (false: keep them aborted and go on after them).
    rerun_aborted: bool = True
    # Print the plan (trials, what to move before each, planned cost) and exit without running anything.
    dry_run: bool = False
    # Print a line per trial (not applicable ones included) besides the progress line.
    verbose: bool = False
    # Simulated trials side by side, the policy answering all lanes in one call, each as alone: a number (8: the
    # learned default 2.8x faster) or auto (1 for now); 1 on hardware.
    lanes: str = "auto"
    # Stopping rules: --stop.width=0.1, --stop.compare=RUN_DIR|hub:USER/NAME, --stop.alpha=0.05.
    stop: StopArgs = field(default_factory=StopArgs)
    # Staging with a calibrated camera: --staging.calibration=PATH, --staging.tolerance=0.02 (metres),
    # --staging.object_size=0.03, --staging.viewer=serve|spawn|none.
    staging: StagingArgs = field(default_factory=StagingArgs)
    # The arm as its own operator (--operator=arm): --arm.tries, --arm.pace, --arm.uncertainty, --arm.unsure,
    # --arm.audit.
    arm: ArmArgs = field(default_factory=ArmArgs)
    # The person at the bench on their phone (--operator=console or arm): --person.page=true serves a page of each
    # trial and the console's answers, --person.lan=true to the local network; --person.notify=URL (docs/phone.md).
    person: PersonArgs = field(default_factory=PersonArgs)


def resume_args(argv: list[str]) -> list[str]:
    """With --resume, start from the run's own config.json, so only the flags that change need repeating."""
    flags = dict(arg.lstrip("-").split("=", 1) for arg in argv if "=" in arg)
    if flags.get("resume", "").lower() not in ("true", "1", "yes") or "config_path" in flags:
        return argv
    stored = Path(flags.get("output_dir", "")) / "config.json"
    return [f"--config_path={stored}", *argv] if "output_dir" in flags and stored.is_file() else argv


# Choices of one session that a resumed run may make differently (the staging camera's included), so they are not
# stored in config.json.
SESSION_CHOICES = ("rerun_aborted", "verbose", "lanes", "staging", "operator_channel", "clock", "person")


# Settings of interleaved runs (--policies), left out of a single-policy run's config.json while at their default.
PAIRING_DEFAULTS = {"policies": None, "blind": False}
# The arm's settings, left out of config.json while at their default (a run without --operator=arm has no use for them).
ARM_DEFAULTS = {"arm": draccus.encode(ArmArgs())}


def config_json(config: Any) -> dict[str, Any]:
    encoded = draccus.encode(config)
    out = {
        k: v
        for k, v in encoded.items()
        if k not in SESSION_CHOICES and {**PAIRING_DEFAULTS, **ARM_DEFAULTS}.get(k, ...) != v
    }
    if isinstance(out.get("stop"), dict) and not out["stop"].get("decided"):
        out["stop"] = {k: v for k, v in out["stop"].items() if k != "decided"}
    return out
