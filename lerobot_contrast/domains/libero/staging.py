"""The LIBERO world behind `libero_sim`: one LeRobot `LiberoEnv` per LIBERO scene, staged by setting init states
(LIBERO's own starts) or by carrying objects to planar poses, then settled with LeRobot's no-op action."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.libero import suites
from lerobot_contrast.domains.libero.config_libero_sim import LiberoSimConfig

# A staged pose equal to a LIBERO init state within this (metres) starts from that init state itself.
SAME_M = 1e-4
# Objects are set down this far above where they rest, so that they settle onto, not into, the table.
DROP_M = 0.002


def find_world(scene: Scene) -> suites.LiberoTaskInfo:
    """The first LIBERO task (over the four suites) whose objects are the scene's."""
    key = suites.world_key(scene.objects)
    for suite in suites.SUITES:
        for info in suites.tasks(suite):
            if suites.world_key(info.objects) == key:
                return info
    raise UserError(
        f"--robot.type=libero_sim stages only LIBERO scenes; no LIBERO task has the objects {', '.join(sorted(key))}"
    )


def matching_init_state(info: suites.LiberoTaskInfo, scene: Scene) -> np.ndarray | None:
    """A LIBERO init state (of any task of this world) whose objects stand where `scene` has them."""
    for other in suites.tasks(info.suite):
        if suites.world_key(other.objects) != suites.world_key(info.objects):
            continue
        for index in range(other.n_init_states):
            poses = suites.init_poses(other, index)
            if all(
                poses[n].distance_to(p) <= SAME_M and abs(poses[n].yaw - p.yaw) <= 1e-3
                for n, p in scene.objects.items()
            ):
                return suites.init_states(other.suite, other.task_id)[index]
    return None


def yaw_quaternion(angle: float) -> np.ndarray:
    return np.array([math.cos(angle / 2.0), 0.0, 0.0, math.sin(angle / 2.0)])


def quaternion_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([
        w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
        w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
        w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
        w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
    ])  # fmt: skip


class World:
    """The LiberoEnv of the LIBERO scene last staged, and its latest observation."""

    def __init__(self, config: LiberoSimConfig) -> None:
        self.config = config
        self.env: Any = None
        self.info: suites.LiberoTaskInfo | None = None
        self.rest: np.ndarray | None = None  # the MuJoCo state objects are set down from (their upright rest)
        self.raw: dict[str, Any] | None = None

    def inner(self) -> Any:
        if self.env is None:
            raise UserError("no LIBERO scene is staged yet; stage an instance before reading the simulator")
        return self.env._env.env

    def _load(self, info: suites.LiberoTaskInfo) -> None:
        from lerobot.envs.libero import LiberoEnv

        self.close()
        self.env = LiberoEnv(
            suites.benchmark(info.suite), info.task_id, info.suite,
            obs_type="pixels_agent_pos",
            observation_width=self.config.observation_width,
            observation_height=self.config.observation_height,
            num_steps_wait=self.config.settle_steps,
            # Every trial's state is staged here (init state or carried objects), so LeRobot's soft reset serves:
            # the model and the renderer are built once per world, not again by each of its two resets.
            hard_reset=False,
        )  # fmt: skip
        self.raw, _ = self.env.reset()
        self.info = info
        self._check_layout()
        self.rest = np.array(self.inner().sim.get_state().flatten())

    def _check_layout(self) -> None:
        inner = self.inner()
        for k, name in enumerate(self.info.objects):
            address = inner.sim.model.get_joint_qpos_addr(inner.objects_dict[name].joints[-1])[0]
            if address != suites.ROBOT_QPOS + suites.FREE_JOINT * k:
                raise RuntimeError(f"LIBERO's model puts {name} at qpos {address}, not where its BDDL order says")

    def stage(self, scene: Scene) -> None:
        info = find_world(scene)
        if self.info is None or suites.world_key(self.info.objects) != suites.world_key(info.objects):
            self._load(info)
        start = matching_init_state(self.info, scene)
        if start is not None:
            self.env._env.set_init_state(start)
        else:
            self._carry(scene)
        self._settle()

    def _carry(self, scene: Scene) -> None:
        """Put moved objects down upright at their new planar poses, and the arm back at its start (free to reset)."""
        sim, rest = self.inner().sim, suites.object_qpos(self.info, self.rest)
        qpos = sim.data.qpos.copy()
        qpos[: suites.ROBOT_QPOS] = self.rest[1 : 1 + suites.ROBOT_QPOS]
        here = self.poses()
        for name, pose in scene.objects.items():
            if here[name].distance_to(pose) <= SAME_M and abs(here[name].yaw - pose.yaw) <= 1e-3:
                continue
            upright = suites.planar(rest[name])
            start = suites.ROBOT_QPOS + suites.FREE_JOINT * list(self.info.objects).index(name)
            quat = quaternion_product(yaw_quaternion(pose.yaw - upright.yaw), rest[name][3:7])
            qpos[start : start + 7] = [pose.x, pose.y, rest[name][2] + DROP_M, *quat]
        sim.data.qpos[:] = qpos
        sim.data.qvel[:] = 0.0
        sim.forward()

    def _settle(self) -> None:
        """Let the objects come to rest for `settle_steps` control periods of physics, the arm held where it was
        staged, and render once: a staged scene is a new episode for robosuite (its step count and horizon restart)."""
        inner = self.inner()
        sim = inner.sim
        hold = sim.data.qpos[: suites.ROBOT_QPOS].copy()
        hold[7:] = self.rest[8 : 1 + suites.ROBOT_QPOS]  # the gripper open, as LeRobot's no-op steps leave it
        substeps = max(1, self.config.settle_steps) * round(inner.control_timestep / inner.model_timestep)
        for _ in range(substeps):
            sim.step()
            sim.data.qpos[: suites.ROBOT_QPOS] = hold
            sim.data.qvel[: suites.ROBOT_QPOS] = 0.0
        sim.forward()
        inner.timestep, inner.done = 0, False
        self.raw = self.env._format_raw_obs(inner._get_observations(force_update=True))

    def observation(self) -> dict[str, Any]:
        if self.raw is None:
            raise UserError("no LIBERO scene is staged yet; stage an instance before observing")
        return self.raw

    def step(self, action: np.ndarray) -> None:
        self.raw, _, _, _, _ = self.env.step(action)

    def poses(self) -> dict[str, Pose]:
        state = np.concatenate([[0.0], self.inner().sim.data.qpos])
        return {name: suites.planar(q) for name, q in suites.object_qpos(self.info, state).items()}

    def close(self) -> None:
        if self.env is not None:
            self.env.close()
        self.env, self.info, self.raw = None, None, None
