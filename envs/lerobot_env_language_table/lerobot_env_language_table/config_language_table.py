"""`--env.type=language_table`: the benchmark's families as tasks, with the keys, fps and success LeRobot reads."""

from __future__ import annotations

from dataclasses import dataclass, field

from lerobot.configs import FeatureType, PolicyFeature
from lerobot.envs.configs import EnvConfig
from lerobot.utils.constants import ACTION, OBS_IMAGES, OBS_STATE

from lerobot_contrast.domains.language_table import FAMILIES, board
from lerobot_env_language_table.errors import EnvFlagError

ALL_FAMILIES = "all"
CAMERA = "top"
# Effector x, y then effector-target x, y: the order of the `language_table_sim` robot's observation.state.
STATE_SIZE = 4


def _features() -> dict[str, PolicyFeature]:
    return {
        ACTION: PolicyFeature(type=FeatureType.ACTION, shape=(2,)),
        "agent_pos": PolicyFeature(type=FeatureType.STATE, shape=(STATE_SIZE,)),
        CAMERA: PolicyFeature(type=FeatureType.VISUAL, shape=(board.IMAGE_HEIGHT, board.IMAGE_WIDTH, 3)),
    }


@EnvConfig.register_subclass("language_table")
@dataclass
class LanguageTableEnvConfig(EnvConfig):
    """Push blocks on the Language-Table board (pymunk physics, 180x320 camera, 2-D effector deltas at 10 Hz).

    `task` is `all` (the five families mixed, as `python -m lerobot_contrast.eval` samples them) or a comma-separated
    list of families, each evaluated as its own task group. Episode seed `s` plays the instance the task samples with
    seed `s`, or, with `instances` (a run directory of `python -m lerobot_contrast.eval`, or its plan.json), the
    run's original instance number `s` modulo their number, so `lerobot-eval --seed=0` plays them in the run's order.
    """

    # `all`, or families separated by commas (each its own task group): block2block, separate, ...
    task: str | None = ALL_FAMILIES
    fps: int = int(board.CONTROL_HZ)
    # Steps before an episode that has not succeeded ends (the benchmark's 200).
    episode_length: int = board.MAX_EPISODE_STEPS
    # The blocks on the board: BLOCK_8, the benchmark's evaluation set.
    block_mode: str = "BLOCK_8"
    # A run directory of `python -m lerobot_contrast.eval` (or its plan.json): play that run's original instances.
    instances: str | None = None
    features: dict[str, PolicyFeature] = field(default_factory=_features)
    features_map: dict[str, str] = field(
        default_factory=lambda: {ACTION: ACTION, "agent_pos": OBS_STATE, CAMERA: f"{OBS_IMAGES}.{CAMERA}"}
    )

    def __post_init__(self) -> None:
        unknown = [family for family in self.families() if family not in FAMILIES]
        if unknown:
            raise EnvFlagError(
                f"--env.task: unknown Language-Table families {', '.join(unknown)}; give {ALL_FAMILIES} or some of: "
                f"{', '.join(FAMILIES)}"
            )
        if self.episode_length < 1:
            raise EnvFlagError(f"--env.episode_length must be a whole number >= 1, got {self.episode_length}")

    def families(self) -> list[str]:
        """The families named by `task`, empty for `all`."""
        task = (self.task or ALL_FAMILIES).strip()
        return [] if task == ALL_FAMILIES else [f.strip() for f in task.split(",") if f.strip()]

    @property
    def gym_kwargs(self) -> dict:
        return {"block_mode": self.block_mode, "max_episode_steps": self.episode_length}

    def create_envs(self, n_envs: int, use_async_envs: bool = False):
        """{task group: {0: a vector env of `n_envs` boards}}: one group `language_table`, or one per family."""
        from lerobot_env_language_table.env import load_instances, make_vector_env

        instances = load_instances(self.instances) if self.instances else None
        groups = {family: family for family in self.families()} or {self.type: None}
        return {
            group: {0: make_vector_env(family, instances, n_envs, use_async_envs, **self.gym_kwargs)}
            for group, family in groups.items()
        }
