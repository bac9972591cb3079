"""One sweep cell, as a Ray worker runs it: its EvalConfig as an Evaluation run by the spine, resumed from its
journal wherever an earlier attempt left one, on the node's own disk where it cannot see the sweep folder. A learned
policy loads once per worker process, not per cell."""

from __future__ import annotations

import dataclasses
import json
import os
import re
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.task import Task
from lerobot_contrast.eval import connect, equipped, planned_evaluation
from lerobot_contrast.policies import PRETRAINED_BUILD, Policy, make_policy, policy_entry
from lerobot_contrast.policies.base import PolicyArgs
from lerobot_contrast.record.journal import read_journal
from lerobot_contrast.record.shared_episodes import FOLDER, SharedEpisodes, weights_digest
from lerobot_contrast.record.sweep_dir import is_complete
from lerobot_contrast.spine.build import make_robot, register_robots
from lerobot_contrast.spine.config import EvalConfig, config_json
from lerobot_contrast.spine.evaluation import run
from lerobot_contrast.sweep.carry import Carry, local_run_dir, pack
from lerobot_contrast.sweep.cells import policy_shares_episodes

if TYPE_CHECKING:
    from lerobot.robots import Robot

# Learned policies loaded in this process, by their settings and the robot features they were built for.
# Scripted policies are not kept: they are cheap to build and hold on to their cell's robot.
_LOADED: dict[str, Policy] = {}
HUB_ID = re.compile(r"[\w.-]+/[\w.-]+")


@dataclass(frozen=True)
class CellOutcome:
    name: str
    status: str  # complete or failed
    trials: int = 0
    seconds: float = 0.0
    cpu_s: float = 0.0  # CPU time of the worker process while it ran the cell
    node: str | None = None  # the Ray node that ran it
    pid: int | None = None  # the worker process that ran it
    policy_loaded: bool = False  # whether it loaded its learned policy, rather than finding it loaded
    error: str | None = None  # one line
    detail: str | None = None  # the traceback of an unexpected error
    gpus: float = 0.0  # the share of GPUs Ray gave the cell (--ray.gpus_per_cell for a policy on cuda)
    cuda_visible_devices: str | None = None  # the GPUs Ray made visible to the cell, where it gave it any
    run_dir: bytes | None = None  # the cell's run directory as a tar, from a node that cannot see the sweep folder


def wants_gpu(policy: PolicyArgs) -> bool:
    return str(policy.device or "").startswith("cuda")


def run_cell(name: str, cfg: EvalConfig, shared: Path | None = None, carry: Carry | None = None) -> CellOutcome:
    """Run (or resume, or find finished) the cell's evaluation in `cfg.output_dir`, taking episodes other cells
    ran from the folder `shared` where given; never raises for the cell's own errors, so one bad cell does not stop
    the sweep. With `carry` (a sweep on a cluster) and no sight of the sweep folder, it runs on this node's disk
    and its run directory comes back in the outcome."""
    start, cpu_start = time.perf_counter(), time.process_time()
    loaded_before = len(_LOADED)
    away = carry is not None and not carry.shares_folder()

    def outcome(status: str, trials: int = 0, error: str | None = None, detail: str | None = None) -> CellOutcome:
        seconds, cpu_s, loaded = time.perf_counter() - start, time.process_time() - cpu_start, len(_LOADED)
        gpus = _gpus()
        packed = pack(Path(cfg.output_dir), carry.recordings) if away and Path(cfg.output_dir).is_dir() else None
        return CellOutcome(
            name, status, trials, seconds, cpu_s, _node(), os.getpid(), loaded > loaded_before, error, detail,
            gpus, os.environ.get("CUDA_VISIBLE_DEVICES") if gpus else None, packed,
        )  # fmt: skip

    try:
        if away:
            cfg = dataclasses.replace(cfg, output_dir=local_run_dir(carry, name))
            shared = carry.local_root() / FOLDER if shared else None
        if carry is not None:
            _check_policy_path(cfg)
        trials = _run(dataclasses.replace(cfg), shared)
    except UserError as error:
        return outcome("failed", error=str(error))
    except Exception as error:
        return outcome(
            "failed", error=f"{type(error).__name__}: {' '.join(str(error).split())}", detail=traceback.format_exc()
        )
    return outcome("complete", trials)


def _check_policy_path(cfg: EvalConfig) -> None:
    """A policy given by a folder must be at that path on the node: Ray does not carry checkpoints."""
    path = cfg.policy.path
    if path and not Path(path).exists() and not HUB_ID.fullmatch(str(path)):
        raise UserError(
            f"policy.path {path} is not on {_where()}: a checkpoint folder must be at that path on every node "
            "(storage they all mount there), or on the Hub (give its repo id)"
        )


def _run(cfg: EvalConfig, shared: Path | None = None) -> int:
    run_dir = Path(cfg.output_dir)
    cfg.resume = (run_dir / "config.json").is_file()  # an earlier attempt, killed or interrupted, started it
    if cfg.resume and is_complete(run_dir):
        return len(read_journal(run_dir / "journal.jsonl"))
    register_robots()  # LeRobot's robots and its policy and robot plugins, as the eval command has them
    planned = planned_evaluation(cfg)
    robot = make_robot(cfg)
    connect(robot)
    try:
        policy = _policy(cfg, robot, planned.task)
        # The cell runs lanes (--lanes, auto by default), answered from one thread: cells are the sweep's parallelism.
        evaluation = dataclasses.replace(
            equipped(cfg, planned, robot, policy, None),
            verbose=False,
            lane_threads=1,
            shared_episodes=_shared(cfg, robot, policy, shared),
        )
        return len(run(evaluation).records)
    finally:
        if robot.is_connected:
            robot.disconnect()


def _policy(cfg: EvalConfig, robot: Robot, task: Task) -> Policy:
    if policy_entry(cfg.policy, cfg.task).build != PRETRAINED_BUILD:
        return make_policy(cfg.policy, robot, task, cfg.rename_map)
    import torch

    torch.set_num_threads(1)  # the cells are the parallelism: one thread each
    encoded = config_json(cfg)
    key = json.dumps([encoded["policy"], encoded["rename_map"], encoded["robot"]], sort_keys=True, default=str)
    if key not in _LOADED:
        _LOADED[key] = make_policy(cfg.policy, robot, task, cfg.rename_map)
    return _LOADED[key]


def _shared(cfg: EvalConfig, robot: Robot, policy: Policy, folder: Path | None) -> SharedEpisodes | None:
    """The episodes shared with other cells, where the instance decides the episode: a simulator whose staging
    rebuilds its whole state, and a learned policy drawing nothing from the trial's randomness (no action noise,
    no language blinding). They are keyed by the weights too, so weights retrained at the same path share nothing
    with the old ones."""
    whole = getattr(robot, "stages_whole_state", False)
    if folder is None or not whole or not policy_shares_episodes(cfg):
        return None
    return SharedEpisodes(folder, config_json(cfg) | {"weights": weights_digest(policy.policy)})


def _node() -> str | None:
    import ray

    return ray.get_runtime_context().get_node_id() if ray.is_initialized() else None


def _where() -> str:
    import ray

    return f"node {ray.util.get_node_ip_address()}" if ray.is_initialized() else "this machine"


def _gpus() -> float:
    import ray

    return ray.get_runtime_context().get_assigned_resources().get("GPU", 0.0) if ray.is_initialized() else 0.0
