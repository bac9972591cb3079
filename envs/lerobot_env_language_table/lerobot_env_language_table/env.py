"""The simulator's gymnasium env with LeRobot's observation keys, and the instances a finished run played."""

from __future__ import annotations

import json
from functools import partial
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.domains.language_table import FAMILIES
from lerobot_contrast.domains.language_table.env import LANGUAGE_TABLE_ID
from lerobot_env_language_table.errors import EnvFlagError

PLAN_FILE = "plan.json"


def load_instances(source: str) -> list[Instance]:
    """The original instances of a run's plan, in the order the run played them (each base once)."""
    path = Path(source).expanduser()
    path = path / PLAN_FILE if path.is_dir() else path
    if not path.is_file():
        raise EnvFlagError(f"--env.instances: {path} does not exist; give a run directory of lerobot_contrast.eval")
    try:
        trials = json.loads(path.read_text(encoding="utf-8"))["trials"]
        bases = {t["base"]["id"]: Instance.from_json(t["base"]) for t in trials if t["perturbation"] is None}
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError):
        raise EnvFlagError(f"--env.instances: {path} is not a plan.json written by lerobot_contrast.eval") from None
    if not bases or any(instance.family not in FAMILIES for instance in bases.values()):
        raise EnvFlagError(f"--env.instances: {path} is not the plan of a Language-Table run (--task=language_table)")
    return list(bases.values())


class LeRobotLanguageTable(gym.ObservationWrapper):
    """`pixels.top` (180x320 RGB) and `agent_pos` (effector and effector-target x, y) out, as lerobot-eval reads them.

    `task_description` (the instruction), `_max_episode_steps` and `info["is_success"]` come from the wrapped env.
    """

    def __init__(self, env: gym.Env, instances: list[Instance] | None = None) -> None:
        super().__init__(env)
        self.instances = instances
        inner = env.observation_space
        low = np.concatenate([inner["effector_translation"].low, inner["effector_target_translation"].low])
        high = np.concatenate([inner["effector_translation"].high, inner["effector_target_translation"].high])
        self.observation_space = spaces.Dict(
            {
                "pixels": spaces.Dict({"top": inner["rgb"]}),
                "agent_pos": spaces.Box(low, high, dtype=np.float32),
            }
        )

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        options = dict(options or {})
        if self.instances and seed is not None:
            options["instance"] = self.instances[seed % len(self.instances)]
        return super().reset(seed=seed, options=options)

    def observation(self, observation: dict[str, np.ndarray]) -> dict[str, Any]:
        state = np.concatenate([observation["effector_translation"], observation["effector_target_translation"]])
        return {"pixels": {"top": observation["rgb"]}, "agent_pos": state.astype(np.float32)}


def make_env(
    family: str | None, instances: list[Instance] | None, block_mode: str, max_episode_steps: int
) -> LeRobotLanguageTable:
    """One board: the registered simulator env (of `family`, or all five), limited to `max_episode_steps`."""
    if instances and family:
        instances = [i for i in instances if i.family == family] or None
    env = gym.make(
        LANGUAGE_TABLE_ID,
        max_episode_steps=max_episode_steps,
        disable_env_checker=True,
        block_mode=block_mode,
        family=family,
    )
    return LeRobotLanguageTable(env, instances)


def make_vector_env(
    family: str | None,
    instances: list[Instance] | None,
    n_envs: int,
    use_async_envs: bool,
    block_mode: str,
    max_episode_steps: int,
) -> gym.vector.VectorEnv:
    """`n_envs` boards stepped together, in worker processes when `use_async_envs` and more than one."""
    make_one = partial(make_env, family, instances, block_mode, max_episode_steps)
    if use_async_envs and n_envs > 1:
        return gym.vector.AsyncVectorEnv(
            [make_one] * n_envs, autoreset_mode=gym.vector.AutoresetMode.SAME_STEP, context="forkserver"
        )
    return gym.vector.SyncVectorEnv([make_one] * n_envs, autoreset_mode=gym.vector.AutoresetMode.SAME_STEP)
