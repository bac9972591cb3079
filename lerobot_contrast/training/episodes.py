"""Demonstration episodes in the simulator, written as a LeRobotDataset v3: the oracle labels every frame.

An *actor* chooses the executed action (the oracle with noise for demonstrations, the learner for DAgger); the
recorded `action` is always the noise-free oracle's action at the visited state, and each frame carries the
privileged targets of `targets.py`.
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import torch

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.language_table import board
from lerobot_contrast.domains.language_table.language_table_sim import ACTION, CAMERA, STATE
from lerobot_contrast.domains.language_table.oracle import PushOracle
from lerobot_contrast.domains.language_table.physics import TabletopPhysics
from lerobot_contrast.domains.language_table.render import TabletopRenderer
from lerobot_contrast.domains.language_table.task import LanguageTableTask
from lerobot_contrast.training import targets

IMAGE_KEY = f"observation.images.{CAMERA}"
# The stored frames are already at the policy's input size (it resizes camera frames with the same op).
IMAGE_SIZE = (72, 128)


class Actor(Protocol):
    """Chooses the executed action from the observation and the oracle's action at that state."""

    def reset(self, instance: Instance) -> None: ...

    def act(self, observation: dict[str, Any], label: np.ndarray) -> np.ndarray: ...


class LaneActor(Protocol):
    """An actor for episodes run side by side (lanes): each lane starts its own episodes (`index`: the episode's
    place in the list), and one call answers every lane mid-episode."""

    def start(self, lane: int, instance: Instance, index: int) -> None: ...

    def act_lanes(
        self, lanes: Sequence[int], observations: Sequence[dict[str, Any]], labels: Sequence[np.ndarray]
    ) -> list[np.ndarray]: ...


# One episode step by step (Simulator.steps): yields (observation, oracle's action), takes the executed action.
Episode = Generator[tuple[dict[str, Any], np.ndarray], np.ndarray, "Outcome"]


def dataset_features() -> dict[str, dict[str, Any]]:
    return {
        IMAGE_KEY: {"dtype": "image", "shape": (*IMAGE_SIZE, 3), "names": ["height", "width", "channels"]},
        "observation.state": {"dtype": "float32", "shape": (len(STATE),), "names": list(STATE)},
        "action": {"dtype": "float32", "shape": (len(ACTION),), "names": list(ACTION)},
        **targets.features(),
    }


def small_image(rgb: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8 camera frame -> the stored (72, 128, 3) uint8 frame, by the policy's own resize."""
    from lerobot_policy_tabletop_pointer.modeling_tabletop_pointer import resize_image

    image = torch.from_numpy(rgb).permute(2, 0, 1).unsqueeze(0).float() / 255
    small = resize_image(image, *IMAGE_SIZE)[0].permute(1, 2, 0)
    return (small * 255).round().clamp(0, 255).to(torch.uint8).numpy()


@dataclass
class Outcome:
    success: bool
    steps: int


class Simulator:
    """Physics, renderer and oracle for one process; `rollout` runs one instance from its start scene."""

    def __init__(self, task: LanguageTableTask) -> None:
        self.task = task
        self.physics = TabletopPhysics()
        self.renderer = TabletopRenderer(board.IMAGE_HEIGHT, board.IMAGE_WIDTH)
        self.oracle = PushOracle(task)

    def _scene(self) -> Scene:
        blocks, (ex, ey) = self.physics.state()
        return Scene(objects={n: Pose(*p) for n, p in blocks.items()}, robot=Pose(ex, ey))

    def observation(self) -> dict[str, Any]:
        blocks, effector = self.physics.state()
        state = np.array([*self.physics.effector, *self.physics.target], np.float32)
        return {"image": self.renderer.render(blocks, effector), "state": state}

    def rollout(self, instance: Instance, actor: Actor, max_steps: int, record: Callable | None = None) -> Outcome:
        """Run `instance` until its goal holds or `max_steps`; `record(frame)` receives each labelled frame."""
        actor.reset(instance)
        steps = self.steps(instance, max_steps, record)
        try:
            observation, label = next(steps)
            while True:
                observation, label = steps.send(actor.act(observation, label))
        except StopIteration as end:
            return end.value

    def steps(self, instance: Instance, max_steps: int, record: Callable | None = None) -> Episode:
        """`instance`'s episode one control step at a time: yields (observation, oracle's action), takes the action
        to execute, and returns the outcome; `record(frame)` receives each labelled frame."""
        robot = instance.scene.robot
        blocks = {n: (p.x, p.y, p.yaw) for n, p in instance.scene.objects.items()}
        self.physics.set_state(blocks, (robot.x, robot.y))
        self.oracle.reset(instance)
        for step in range(max_steps):
            scene = self._scene()
            if self.task.is_achieved(instance, scene):
                return Outcome(True, step)
            observation = self.observation()
            label = self.oracle.act(scene, self.physics.target)
            executed = yield observation, label
            if record is not None:
                record(self._frame(instance, scene, observation, label))
            self.physics.step(np.clip(executed, -board.MAX_ACTION, board.MAX_ACTION))
        return Outcome(self.task.is_achieved(instance, self._scene()), max_steps)

    def _frame(self, instance: Instance, scene: Scene, observation: dict[str, Any], label: np.ndarray) -> dict:
        return {
            IMAGE_KEY: small_image(observation["image"]),
            "observation.state": observation["state"],
            "action": label.astype(np.float32),
            **targets.frame_targets(instance, scene),
            "task": instance.instruction,
        }


@dataclass
class NoisyOracle:
    """Executes the oracle's action plus Gaussian noise, so demonstrations visit states just off its path."""

    noise_std: float
    rng: np.random.Generator

    def reset(self, instance: Instance) -> None:
        pass

    def act(self, observation: dict[str, Any], label: np.ndarray) -> np.ndarray:
        return label + self.rng.normal(0.0, self.noise_std, 2)


def open_dataset(root: Path, repo_id: str):
    """The demonstration dataset at `root`: resumed when it exists, created otherwise."""
    from lerobot.datasets import LeRobotDataset

    if (root / "meta" / "info.json").exists():
        return LeRobotDataset.resume(repo_id, root=root)
    return LeRobotDataset.create(
        repo_id, fps=int(board.CONTROL_HZ), features=dataset_features(), root=root, use_videos=False
    )


def record_episodes(
    dataset, simulator: Simulator, instances: list[Instance], actor: Actor, max_steps: int, lanes: int = 1
) -> list[Outcome]:
    """One dataset episode per instance (an instance already achieved at its start records nothing); any simulator
    with `rollout(instance, actor, max_steps, record=...)`, the apartment's included. An actor with `act_lanes` runs
    `lanes` episodes side by side, each recorded in the instances' order when its turn comes."""
    if lanes > 1 and hasattr(actor, "act_lanes"):
        frames: list[list[dict] | None] = [[] for _ in instances]
        ended: set[int] = set()

        def write(index: int) -> None:  # the episodes ended so far, up to the first still running, in order
            ended.add(index)
            head = next((i for i, episode in enumerate(frames) if episode is not None), len(frames))
            while head in ended:
                for frame in frames[head]:
                    dataset.add_frame(frame)
                if dataset.has_pending_frames():
                    dataset.save_episode()
                frames[head], head = None, head + 1

        records = [episode.append for episode in frames]
        return side_by_side(actor, simulator, instances, max_steps, lanes, records, write)
    outcomes = []
    for instance in instances:
        outcome = simulator.rollout(instance, actor, max_steps, record=dataset.add_frame)
        if dataset.has_pending_frames():
            dataset.save_episode()
        outcomes.append(outcome)
    return outcomes


def side_by_side(
    actor: LaneActor,
    simulator: Simulator,
    instances: Sequence[Instance],
    max_steps: int,
    lanes: int,
    records: Sequence[Callable] | None = None,
    ended: Callable[[int], None] = lambda index: None,
) -> list[Outcome]:
    """Each instance's outcome, `lanes` simulators (`simulator` and copies) running the episodes side by side and
    `actor` answering all of them in one call per control step; `records[i]` receives episode i's frames, and
    `ended(i)` is called as episode i ends."""
    simulators = [simulator, *(Simulator(simulator.task) for _ in range(min(lanes, len(instances)) - 1))]
    waiting = list(range(len(instances)))[::-1]
    outcomes: list[Outcome | None] = [None] * len(instances)
    running: dict[int, tuple[int, Episode, tuple[dict[str, Any], np.ndarray]]] = {}
    while waiting or running:
        for lane, lane_simulator in enumerate(simulators):
            while lane not in running and waiting:
                index = waiting.pop()
                actor.start(lane, instances[index], index)
                steps = lane_simulator.steps(instances[index], max_steps, records[index] if records else None)
                _advance(running, outcomes, lane, index, steps, lambda episode: next(episode), ended)
        order = sorted(running)
        if not order:
            continue
        actions = actor.act_lanes(order, [running[n][2][0] for n in order], [running[n][2][1] for n in order])
        for lane, action in zip(order, actions, strict=True):
            index, steps, _ = running[lane]
            _advance(running, outcomes, lane, index, steps, lambda episode, a=action: episode.send(a), ended)
    return outcomes


def _advance(
    running: dict, outcomes: list, lane: int, index: int, steps: Episode, step: Callable, ended: Callable
) -> None:
    """One step of lane `lane`'s episode: still running, or its outcome stored and the lane free."""
    try:
        running[lane] = (index, steps, step(steps))
    except StopIteration as end:
        outcomes[index] = end.value
        running.pop(lane, None)
        ended(index)
