"""The SO-101 moving itself through LeRobot's `so101_follower` alone: its joint readings, where its jaws are (forward
kinematics on the arm's model), and slow, interpolated motions through the planner's waypoints that stop at once
when told to. Used by the arm operator that stages trials itself; nothing here reads a simulator."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import mujoco
import numpy as np

from lerobot_contrast.clock.robot_clock import robot_clock
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.so101 import arm, reach

STEP_HZ = 30.0  # goals sent this often while moving: LeRobot's own teleoperation rate
SETTLE_S = 0.3  # after the last goal, the servos close the rest of the way
# Folded as at rest, turned to the side: at rest the jaws hang over the workspace's near edge, hiding what lies there.
ASIDE = {**arm.REST, "shoulder_pan": math.radians(100)}
READ_RETRIES = 3  # a status packet lost on a busy bus is asked for again before the arm counts as gone
HOLD_GAP = 0.02  # rad: a closed gripper this far short of its goal is held open by an object


class Stopped(UserError):
    """The stop key was pressed while the arm moved; it holds where it was."""


class ArmMotion:
    """`robot`: a connected so101_follower; `model`: the arm's MuJoCo model (for forward kinematics); `pace`: each
    motion's time as a multiple of the planned one (larger is slower); `stop`: asked between steps, True halts;
    `reached`: called at each waypoint (to keep what the motion has spent so far)."""

    def __init__(
        self,
        robot: Any,
        model: mujoco.MjModel,
        pace: float,
        stop: Callable[[], bool],
        reached: Callable[[], None] = lambda: None,
    ) -> None:
        self.robot, self.model, self.pace, self.stop, self.reached = robot, model, pace, stop, reached
        self.data = mujoco.MjData(model)
        self.moving_s = 0.0  # seconds spent moving, all told
        self.goal: dict[str, float] = {}  # the joint goals last sent (radians)
        # Each joint's calibration offset (radians, so101/marker.py): its true angle is its reading plus this. Joint
        # angles in and out of this class are true ones; the servos are read and commanded through the offsets.
        self.offsets: dict[str, float] = {}

    def joints(self) -> dict[str, float]:
        """The arm's joint angles (radians): its servos' readings plus their offsets."""
        positions = self.robot.bus.sync_read("Present_Position", num_retry=READ_RETRIES)
        return {name: arm.from_lerobot(name, float(positions[name])) + self.offsets.get(name, 0.0)
                for name in arm.MOTOR_NAMES}  # fmt: skip

    def jaws(self, size: float, joints: Mapping[str, float] | None = None) -> tuple[float, float, float]:
        """Where an object `size` wide held between the pads would be (x, y, z, metres)."""
        joints = joints or self.joints()
        for name in reach.ARM_JOINTS:
            self.data.qpos[self.model.joint(name).qposadr[0]] = joints[name]
        mujoco.mj_kinematics(self.model, self.data)
        site = self.data.site(reach.SITE)
        where = site.xpos + site.xmat.reshape(3, 3) @ reach.grasp_point(self.model, size)
        return float(where[0]), float(where[1]), float(where[2])

    def holding(self, joints: Mapping[str, float]) -> bool:
        """Whether the jaws hold something: told to close, they stopped short of where they were told to go (a
        servo blocked by what it grips reads off its goal, whatever its calibration's offset)."""
        goal = self.goal.get(arm.GRIPPER)
        return goal is not None and goal < reach.OPEN / 2 and joints[arm.GRIPPER] - goal > HOLD_GAP

    def links(self, joints: Mapping[str, float] | None = None, per_link: int = 4) -> np.ndarray:
        """Points (N, 3) covering the arm, its base to its jaws: every part's centre and `per_link` points along each
        link, for masking its image."""
        self.jaws(0.0, joints)  # places the model at the joints
        root = self.model.body_rootid[self.model.joint(arm.MOTOR_NAMES[0]).bodyid[0]]
        bodies = [b for b in range(1, self.model.nbody) if self.model.body_rootid[b] == root]
        parts = [self.data.geom_xpos[g] for g in range(self.model.ngeom) if self.model.geom_bodyid[g] in bodies]
        chain = [self.data.xpos[self.model.joint(name).bodyid[0]] for name in arm.MOTOR_NAMES]
        chain.append(self.data.site(reach.SITE).xpos)
        share = np.linspace(0.0, 1.0, per_link, endpoint=False)[:, None]
        along = [a + share * (b - a) for a, b in zip(chain, chain[1:], strict=False)]
        return np.concatenate([np.array(parts).reshape(-1, 3), *along, chain[-1][None]])

    def follow(self, waypoints: Sequence[reach.Waypoint]) -> None:
        """Move through `waypoints`, each joint interpolated from where the last goal left it."""
        start = self.joints()
        for waypoint in waypoints:
            goal = {name: waypoint.goals.get(name, start[name]) for name in start}
            self._glide(start, goal, waypoint.seconds * self.pace)
            self.reached()
            start = goal
        robot_clock().sleep(SETTLE_S)
        self.moving_s += SETTLE_S

    def _glide(self, start: Mapping[str, float], goal: Mapping[str, float], seconds: float) -> None:
        steps = max(1, math.ceil(seconds * STEP_HZ))
        clock = robot_clock()
        for step in range(1, steps + 1):
            if self.stop():
                raise Stopped("the stop key was pressed while the arm was staging; it holds where it was")
            tick = clock.now()
            share = 0.5 - 0.5 * math.cos(math.pi * step / steps)  # ease in and out: no jerk at either end
            angles = {name: start[name] + share * (goal[name] - start[name]) for name in goal}
            self.robot.send_action(arm.lerobot_action({n: a - self.offsets.get(n, 0.0) for n, a in angles.items()}))
            self.goal = angles
            clock.sleep(1.0 / STEP_HZ - (clock.now() - tick), watched=False)  # the camera looks once it settles
            self.moving_s += 1.0 / STEP_HZ

    def rest(self, gripper: float | None = None) -> None:
        """Back to the rest pose, clear of the workspace and out of the camera's way; `gripper` (radians) held."""
        goals = dict(arm.REST) if gripper is None else {**arm.REST, arm.GRIPPER: gripper}
        self.follow([reach.Waypoint("rest", goals, 1.5)])

    def open_and_withdraw(self) -> None:
        """Let go of whatever the jaws hold, lift away from it, and fold aside, out of the camera's view of the
        workspace (after an episode, and before staging: the camera looks then)."""
        here = self.joints()
        x, y, z = self.jaws(0.0, here)
        opened = {**here, arm.GRIPPER: reach.OPEN}
        try:
            lifted = reach.solve(self.model, reach.grasp_point(self.model, 0.0), np.array([x, y, max(z, 0.0) + reach.HOVER]),
                                 None, here)  # fmt: skip
            steps = [
                reach.Waypoint("open", opened, 0.5),
                reach.Waypoint("lift", {**lifted, arm.GRIPPER: reach.OPEN}, 0.8),
            ]
        except reach.Unreachable:  # straight up is out of reach here: open and go back as it can
            steps = [reach.Waypoint("open", opened, 0.5)]
        self.follow([*steps, reach.Waypoint("aside", {**ASIDE, arm.GRIPPER: reach.OPEN}, 2.0)])
