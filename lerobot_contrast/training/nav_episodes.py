"""Navigation episodes in the simulated apartment, written as a LeRobotDataset v3: the teacher labels every frame.

An *actor* chooses the executed command (the teacher with random slips for demonstrations, the learner for DAgger);
the recorded `action` is always the teacher's command at the visited state, and each frame carries the
privileged targets of `nav_teacher`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import torch
from lerobot_policy_vln_navigator.configuration_vln_navigator import COMMANDS, STATE_NAMES
from lerobot_policy_vln_navigator.modeling_vln_navigator import resize_image

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.domains.vln.apartment import Apartment, CameraSpec, RayCaster
from lerobot_contrast.domains.vln.task import VLNTask
from lerobot_contrast.training.nav_teacher import SHAPES, Teacher, one_hot

IMAGE_KEY = "observation.images.front"
PREFIX = "observation.privileged."
# Stored frames are already at the policy's input size; they are rendered at RENDER_SIZE and area-averaged down
# (the policy averages a robot's full-size frames the same way).
IMAGE_SIZE = (48, 64)
RENDER_SIZE = (144, 192)
FORWARD_M, TURN = 0.25, math.radians(30.0)
FPS = 5


class Actor(Protocol):
    def reset(self, instance: Instance) -> None: ...

    def act(self, observation: dict[str, Any], label: str) -> str: ...


def dataset_features() -> dict[str, dict[str, Any]]:
    return {
        IMAGE_KEY: {"dtype": "image", "shape": (*IMAGE_SIZE, 3), "names": ["height", "width", "channels"]},
        "observation.state": {"dtype": "float32", "shape": (len(STATE_NAMES),), "names": list(STATE_NAMES)},
        "action": {"dtype": "float32", "shape": (len(COMMANDS),), "names": [f"{c}.vel" for c in COMMANDS]},
        **{PREFIX + name: {"dtype": "float32", "shape": shape, "names": None} for name, shape in SHAPES.items()},
    }


def small_image(rgb: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8 -> the stored (48, 64, 3) uint8 frame: block means (what area resizing does at an integer
    factor), computed in numpy because it is 20x faster than torch's op on one small frame."""
    h, w = IMAGE_SIZE
    fy, fx = rgb.shape[0] // h, rgb.shape[1] // w
    if (fy * h, fx * w) == rgb.shape[:2]:
        small = rgb.reshape(h, fy, w, fx, 3).mean(axis=(1, 3))
        return np.round(small).astype(np.uint8)
    image = torch.from_numpy(rgb).permute(2, 0, 1).unsqueeze(0).float() / 255
    return (resize_image(image, h, w)[0].permute(1, 2, 0) * 255).round().clamp(0, 255).to(torch.uint8).numpy()


@dataclass
class Outcome:
    success: bool
    progress: float
    spl: float
    steps: int


class NavSimulator:
    """The apartment, its camera and the judge for one process; `rollout` runs one instance from its start."""

    def __init__(self, task: VLNTask | None = None, camera: bool = True) -> None:
        self.task = task or VLNTask()
        self.camera = camera  # scripted actors read the state alone: no need to render
        self.world = Apartment(robot_radius=0.18, collision="slide")
        self.caster = RayCaster(CameraSpec(RENDER_SIZE[1], RENDER_SIZE[0]))

    def observation(self) -> dict[str, Any]:
        pose = self.world.pose
        rgb, depth = self.caster.render(self.world.room, self.world.footprints, pose) if self.camera else (None, None)
        state = np.array([pose.x, pose.y, pose.yaw, 0.0, 0.0, float(self.world.bumped)], np.float32)
        return {"image": rgb, "depth": depth, "state": state}

    def step(self, command: str) -> None:
        if command == "forward":
            self.world.forward(FORWARD_M)
        elif command in ("turn_left", "turn_right"):
            self.world.rotate(TURN if command == "turn_left" else -TURN)

    def rollout(self, instance: Instance, actor: Actor, max_steps: int, record: Callable | None = None) -> Outcome:
        """Run `instance` until the actor stops or `max_steps`; `record(frame)` receives each labelled frame."""
        teacher = Teacher(instance)
        start = Pose.from_json(instance.goal["start"])
        self.world.set_scene(instance.scene.objects, start)
        actor.reset(instance)
        path, phase = [start], 0
        for _ in range(max_steps):
            pose = self.world.pose
            phase = teacher.phase(phase, pose)
            label = teacher.act(pose, phase)
            observation = self.observation()
            executed = actor.act(observation, label)
            if record is not None:
                record(self._frame(instance, teacher, pose, observation, label))
            if executed == "stop":
                break
            self.step(executed)
            path.append(self.world.pose)
        return self._outcome(instance, path, len(path))

    def _outcome(self, instance: Instance, path: list[Pose], steps: int) -> Outcome:
        judgement = self.task.judge(instance, path, self.world.scene())
        length = sum(math.dist((a.x, a.y), (b.x, b.y)) for a, b in zip(path, path[1:], strict=False))
        reference = self.task.reference_length(instance) or 0.0
        spl = float(judgement.success) * reference / max(length, reference, 1e-9)
        return Outcome(judgement.success, judgement.progress, spl, steps)

    def _frame(self, instance, teacher: Teacher, pose: Pose, observation, label: str) -> dict:
        targets = teacher.targets(pose)
        return {
            IMAGE_KEY: small_image(observation["image"]),
            "observation.state": observation["state"],
            "action": one_hot(label),
            **{PREFIX + name: value for name, value in targets.items()},
            "task": instance.instruction,
        }


@dataclass
class SlippingTeacher:
    """Executes the teacher's command, but a random move at rate `slip`, so demonstrations leave its path."""

    slip: float
    rng: np.random.Generator
    moves: tuple[str, ...] = field(default=("forward", "turn_left", "turn_right"))

    def reset(self, instance: Instance) -> None:
        pass

    def act(self, observation: dict[str, Any], label: str) -> str:
        if label != "stop" and self.rng.random() < self.slip:
            return self.moves[int(self.rng.integers(len(self.moves)))]
        return label


def open_dataset(root: Path, repo_id: str):
    """The demonstration dataset at `root`: resumed when it exists, created otherwise."""
    from lerobot.datasets import LeRobotDataset

    if (root / "meta" / "info.json").exists():
        return LeRobotDataset.resume(repo_id, root=root)
    return LeRobotDataset.create(repo_id, fps=FPS, features=dataset_features(), root=root, use_videos=False)
