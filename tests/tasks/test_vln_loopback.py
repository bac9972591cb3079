"""End to end without the eval CLI: the host with the simulated apartment, the LoCoBot client over loopback,
the scripted navigator, and the task's judge."""

from __future__ import annotations

import math
import time
from itertools import pairwise

import numpy as np
import pytest
from lerobot_robot_locobot import Locobot
from lerobot_robot_locobot.host import HostThread

from lerobot_contrast.contrast import DistanceCost, Outcome, make_plan
from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.evaluate import LoopState, run_trials
from lerobot_contrast.runners.episode import SceneIO, TrialContext
from lerobot_contrast.tasks.vln import VLNTask
from lerobot_contrast.tasks.vln.policy import RouteFollower
from tests.robots.locobot_helpers import FREE_PORTS, client_config
from tests.tasks.test_vln_policy import context_for

TASK = VLNTask()


def episode(robot: Locobot, policy: RouteFollower, context: TrialContext, max_steps: int = 150) -> Outcome:
    """What a robot runner does with a SceneIO robot: stage, roll out until stop, read the scene, judge."""
    started = time.perf_counter()
    instance = context.instance
    robot.stage_scene(instance.scene)
    policy.reset(context)
    path = []
    for _ in range(max_steps):
        observation = robot.get_observation()
        path.append(Pose(observation["odom.x"], observation["odom.y"], observation["odom.theta"]))
        robot.send_action(policy.act(observation))
        if robot.stop_requested:
            break
    scene_after = robot.read_scene()
    judgement = TASK.judge(instance, path, scene_after)
    return Outcome(
        success=judgement.success,
        progress=judgement.progress,
        steps=len(path),
        path_length=sum(math.dist((a.x, a.y), (b.x, b.y)) for a, b in pairwise(path)),
        scene_after=scene_after,
        duration_s=time.perf_counter() - started,
        reference_length=TASK.reference_length(instance),
        extra={"ndtw": TASK.ndtw(instance, path)},
    )


@pytest.fixture
def robot(tmp_path):
    with HostThread(FREE_PORTS) as host:
        robot = Locobot(client_config(host.ports, tmp_path))
        robot.connect()
        yield robot
        robot.disconnect()


def test_a_vln_episode_over_loopback_reaches_both_subgoals(robot):
    assert isinstance(robot, SceneIO) and robot.supports_scene_io
    instance = TASK.examples[0]
    outcome = episode(robot, RouteFollower(), context_for(instance))
    assert outcome.success and outcome.progress == 1.0
    assert outcome.scene_after.objects == instance.scene.objects  # the robot moved no furniture
    assert 0.7 < outcome.reference_length / outcome.path_length <= 1.0
    assert outcome.extra["ndtw"] > 0.5


@pytest.mark.slow
def test_the_shipped_contrast_evaluation_runs_its_75_trials_in_a_few_minutes(tmp_path):
    rng = np.random.default_rng(0)
    plan = make_plan("contrast", TASK.sample(5, rng), list(TASK.perturbations), repeats=3, rng=rng)
    policy = RouteFollower()
    with HostThread(FREE_PORTS) as host:
        robot = Locobot(client_config(host.ports, tmp_path, camera_width=320, camera_height=240))
        robot.connect()
        started = time.perf_counter()
        records = list(
            run_trials(
                plan,
                TASK,
                DistanceCost(),
                None,
                0,
                LoopState(TASK.storage_scene()),
                lambda c: episode(robot, policy, c),
            )
        )
        elapsed = time.perf_counter() - started
        robot.disconnect()
    print(f"75 trials at 320x240 in {elapsed:.1f} s")
    assert len(records) == 75 and all(r.status == "done" and r.success for r in records)
    assert elapsed < 300
