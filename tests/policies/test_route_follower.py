"""The scripted route follower drives the simulated apartment to both subgoals, from odometry alone."""

from __future__ import annotations

import math
from itertools import pairwise

import numpy as np
import pytest
from navigation_protocol import discrete_command

from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.contrast.task import perturb
from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.domains.vln import VLNTask
from lerobot_contrast.domains.vln.apartment import Apartment
from lerobot_contrast.policies.route_follower import RouteFollower

TASK = VLNTask()


def context_for(instance, base=None, seed: int = 0) -> TrialContext:
    return TrialContext(
        index=0, instance=instance, base=base or instance, current=instance.scene, planned_cost=0.0,
        staging="reset", rng=np.random.default_rng(seed), planned_trials=1,
    )  # fmt: skip


def drive(policy, context, odom_offset=(0.0, 0.0, 0.0), max_steps: int = 200) -> tuple[list[Pose], int]:
    """Run the policy in the apartment; odometry reads in a frame shifted by `odom_offset`."""
    apartment = Apartment()
    apartment.set_scene(context.instance.scene.objects, context.instance.scene.robot)
    policy.reset(context)
    path, (dx, dy, dtheta) = [apartment.pose], odom_offset
    for step in range(1, max_steps + 1):
        pose = apartment.pose
        c, s = math.cos(dtheta), math.sin(dtheta)
        odom = {"odom.x": dx + c * pose.x - s * pose.y, "odom.y": dy + s * pose.x + c * pose.y}
        odom["odom.theta"], odom["bumper"] = pose.yaw + dtheta, float(apartment.bumped)
        command = discrete_command(policy.act(odom))
        if command == "stop":
            return path, step
        if command == "forward":
            apartment.forward(0.25)
        else:
            apartment.rotate(math.radians(30) * (1 if command == "turn_left" else -1))
        path.append(apartment.pose)
    return path, max_steps


@pytest.mark.parametrize("instance", TASK.examples, ids=lambda i: i.id)
def test_it_completes_every_shipped_instance_and_its_perturbations(instance):
    for name in (None, "LB", "S", "SB"):
        target = (
            instance
            if name is None
            else perturb(TASK, TASK.perturbations.get(name), instance, np.random.default_rng(0))
        )
        path, steps = drive(RouteFollower(), context_for(target, instance))
        judgement = TASK.judge(target, path, target.scene.with_robot(path[-1]))
        assert judgement.success and steps < 150, (name, steps)
        assert TASK.reference_length(target) <= sum(math.dist((a.x, a.y), (b.x, b.y)) for a, b in pairwise(path))


def test_it_anchors_odometry_to_the_start_pose():
    instance = TASK.examples[2]
    path, _ = drive(RouteFollower(), context_for(instance), odom_offset=(-3.0, 1.5, 2.0))
    assert TASK.judge(instance, path, instance.scene.with_robot(path[-1])).success


def test_a_language_blind_follower_misses_a_changed_final_goal():
    base = TASK.examples[0]
    changed = perturb(TASK, TASK.perturbations.get("LB"), base, np.random.default_rng(0))
    path, _ = drive(RouteFollower(language_blind=1.0), context_for(changed, base))
    assert TASK.judge(changed, path, changed.scene.with_robot(path[-1])).progress == 0.5
    assert TASK.judge(base, path, base.scene.with_robot(path[-1])).success  # it did the old instruction
