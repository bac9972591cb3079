"""A scripted baseline for VLN (task: vln, on vln_sim or the LoCoBot): plan the shortest route on the map, follow it with VLN-CE discrete actions.

Limits, so its numbers are read for what they are:
- it is privileged: it reads the subgoal objects from the instance's goal and the furniture from its scene,
  never the instruction text or the camera. Under ΔL and ΔLB it is perfect by construction, so it measures
  the environment and the evaluation plumbing, not language understanding (`language_blind` simulates a
  policy that ignores changed wording; `action_noise` a clumsy one);
- it trusts odometry, anchored to the instance's start pose on its first observation: on a real base, drift
  and wheel slip go uncorrected, and furniture placed away from where the scene says is not seen;
- turns are quantised (30 degrees by default) and steps are 0.25 m, so it zigzags around the route and its
  path is longer than the reference (SPL below 1 even when it succeeds);
- after a collision it replans from where it is; in a dead end it may spend its step budget turning."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np
from navigation_protocol import one_hot

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.contrast.task import Task
from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.domains.vln import routes
from lerobot_contrast.domains.vln.task import VLNTask
from lerobot_contrast.policies.base import PolicyArgs, PolicyError

if TYPE_CHECKING:
    from lerobot.robots import Robot

# The route is planned this far inside the success radius, so stopping near its end counts as reached.
PLAN_MARGIN_M = 0.3
REACHED_MARGIN_M = 0.05
# Routes keep this much more than the robot's radius from furniture where they can: 30 degree headings and
# 0.25 m steps do not thread gaps a few centimetres wider than the robot.
CLEARANCE_M = 0.12
WAYPOINT_REACHED_M = 0.15
RANDOM_COMMANDS = ("forward", "turn_left", "turn_right")


def build(args: PolicyArgs, robot: Robot, task: Task, rename_map: Mapping[str, str]) -> RouteFollower:
    if not isinstance(task, VLNTask) or not hasattr(robot.config, "forward_m"):
        raise PolicyError("--policy.type=route_follower navigates --task=vln on --robot.type=vln_sim or locobot only")
    return RouteFollower(robot.config.forward_m, robot.config.turn_deg, args.language_blind)


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2 * math.pi) - math.pi


class RouteFollower:
    """RobotPolicy for the discrete action mode of vln_sim and the LoCoBot (see the module docstring for its limits)."""

    name = "vln_route_follower"

    def __init__(
        self, forward_m: float = 0.25, turn_deg: float = 30.0, language_blind: float = 0.0, action_noise: float = 0.0
    ) -> None:
        self.forward_m, self.turn = forward_m, math.radians(turn_deg)
        self.language_blind, self.action_noise = language_blind, action_noise
        self.rng = np.random.default_rng(0)
        self.goal: Instance | None = None
        self.waypoints: list[np.ndarray] = []
        self.previous = np.zeros(2)  # the point the current waypoint is approached from
        self.anchor: tuple[float, float, float] | None = None
        self.reached = 0  # subgoals passed so far

    def reset(self, context: TrialContext) -> None:
        self.rng = context.rng
        instance = context.instance
        if self.rng.random() < self.language_blind:  # follows the base instruction whatever was said
            instance = instance.derive(goal={**instance.goal, "subgoals": context.base.goal["subgoals"]})
        self.goal, self.anchor, self.reached = instance, None, 0
        self._plan(Pose.from_json(instance.goal["start"]))

    def act(self, observation: dict[str, Any]) -> dict[str, float]:
        pose = self._pose(observation)
        subgoals = self._subgoals()
        while self.reached < len(subgoals) - 1 and self._near(subgoals[self.reached], pose):
            self.reached += 1
        if self.reached == len(subgoals) - 1 and self._near(subgoals[-1], pose):
            return one_hot("stop")
        if observation.get("bumper", 0.0) > 0.5:
            self._plan(pose)
        if self.action_noise and self.rng.random() < self.action_noise:
            return one_hot(RANDOM_COMMANDS[int(self.rng.integers(len(RANDOM_COMMANDS)))])
        while self.waypoints and self._passed(self.waypoints[0], pose):
            self.previous = self.waypoints.pop(0)
        if not self.waypoints:
            self._plan(pose)
        if not self.waypoints:
            return one_hot("stop")
        target = self.waypoints[0]
        error = _wrap(math.atan2(target[1] - pose.y, target[0] - pose.x) - pose.yaw)
        if abs(error) > self.turn / 2:
            return one_hot("turn_left" if error > 0 else "turn_right")
        return one_hot("forward")

    def _pose(self, observation: dict[str, Any]) -> Pose:
        """The robot's pose in the scene frame: odometry re-anchored so its first reading is the start pose."""
        odom = (observation["odom.x"], observation["odom.y"], observation["odom.theta"])
        assert self.goal is not None, "reset() before act()"
        start = Pose.from_json(self.goal.goal["start"])
        if self.anchor is None:
            self.anchor = (start.yaw - odom[2], odom[0], odom[1])
        rotation, ox, oy = self.anchor
        dx, dy = odom[0] - ox, odom[1] - oy
        c, s = math.cos(rotation), math.sin(rotation)
        return Pose(start.x + c * dx - s * dy, start.y + s * dx + c * dy, _wrap(odom[2] + rotation))

    def _subgoals(self) -> list[str]:
        assert self.goal is not None, "reset() before act()"
        return list(self.goal.goal["subgoals"])

    def _near(self, name: str, pose: Pose) -> bool:
        """Within the success radius (less a little, so the judge agrees) of furniture `name`."""
        assert self.goal is not None
        distance = routes.distance_to_object(self.goal.scene, name, np.array([[pose.x, pose.y]]))[0]
        return bool(distance <= self.goal.goal["radius"] - REACHED_MARGIN_M)

    def _passed(self, waypoint: np.ndarray, pose: Pose) -> bool:
        """Close to the waypoint, or beyond it along the route (steps of 0.25 m at 30 degree headings rarely
        hit a point exactly)."""
        here = np.array([pose.x, pose.y])
        return bool(
            np.linalg.norm(here - waypoint) < WAYPOINT_REACHED_M or (here - waypoint) @ (waypoint - self.previous) > 0
        )

    def _plan(self, start: Pose) -> None:
        """Route from `start` through the subgoals not reached yet, planned inside the success radius."""
        assert self.goal is not None
        remaining = self._subgoals()[self.reached :]
        radius = max(0.05, self.goal.goal["radius"] - PLAN_MARGIN_M)
        route = None
        for clearance in (CLEARANCE_M, 0.0):  # keep off the furniture where there is room, squeeze where not
            route = route or routes.plan(self.goal.scene, start, remaining, radius, routes.ROBOT_RADIUS + clearance)
        self.previous = np.array([start.x, start.y])
        self.waypoints = [] if route is None else [np.asarray(p) for p in route.points[1:]]
