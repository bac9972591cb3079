"""The learned VLN default (`vln_navigator`): it loads through LeRobot's factory from the shipped weights, reads only
what a LoCoBot gives (RGB, aligned depth, odometry, the instruction), trains on privileged targets, and makes progress
on held-out arrangements in the simulator and over the loopback LoCoBot host; a robot without depth is one line."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from lerobot.configs import PreTrainedConfig
from lerobot.policies import get_policy_class
from lerobot_policy_vln_navigator import WEIGHTS, VLNNavigatorConfig, VLNNavigatorPolicy
from lerobot_policy_vln_navigator.configuration_vln_navigator import DEPTH_KEY, PRIVILEGED_PREFIX
from lerobot_robot_locobot import Locobot
from lerobot_robot_locobot.host import HostThread

from lerobot_contrast import PolicyArgs, load_task, make_policy
from lerobot_contrast.domains.vln import sampler
from lerobot_contrast.domains.vln.config_vln_sim import VLNSimConfig
from lerobot_contrast.domains.vln.vln_sim import VLNSim
from lerobot_contrast.policies import POLICIES, policy_entry
from lerobot_contrast.policies.pretrained import PolicyLoadError, PretrainedPolicy
from lerobot_contrast.spine.runner import RobotRunner
from tests.policies.test_route_follower import context_for
from tests.robots.locobot_helpers import FREE_PORTS, client_config

TASK = load_task("vln")
# A small fixed set of evaluation-split arrangements (training never sees one), and the progress the shipped
# weights must keep on it (they make 0.875 on it; 0.784 on 250 held-out arrangements, see TRAINING.md).
FIXED = sampler.sample_arrangements(4, "eval", 77, TASK.radius)
PROGRESS_FLOOR = 0.6


def mean_progress(robot) -> float:
    policy = make_policy(PolicyArgs(), robot, TASK)
    robot.connect()
    try:
        runner = RobotRunner(robot, policy, TASK, operator=None, fps=None, max_steps=120)
        return float(np.mean([runner(context_for(instance)).progress for instance in FIXED]))
    finally:
        robot.disconnect()


def test_the_shipped_policy_loads_through_lerobots_factory_and_is_the_vln_default():
    config = PreTrainedConfig.from_pretrained(str(WEIGHTS))
    assert isinstance(config, VLNNavigatorConfig) and get_policy_class(config.type) is VLNNavigatorPolicy
    assert not any(key.startswith(PRIVILEGED_PREFIX) for key in config.input_features)
    assert DEPTH_KEY in config.input_features
    assert sum(p.stat().st_size for p in WEIGHTS.iterdir()) < 20e6
    assert policy_entry(PolicyArgs(), "vln") is POLICIES["vln_navigator"]
    assert policy_entry(PolicyArgs(), "language_table") is not POLICIES["vln_navigator"]
    policy = make_policy(PolicyArgs(), VLNSim(VLNSimConfig(camera_width=160, camera_height=120)), TASK)
    assert isinstance(policy, PretrainedPolicy) and policy.name == "vln_navigator"


def test_forward_trains_every_head_from_privileged_targets_that_are_never_inputs():
    policy = VLNNavigatorPolicy(VLNNavigatorConfig(vocabulary=["go", "past", "the", "bed", "desk", "stop", "at"]))
    b = 4
    batch = {
        "observation.images.front": torch.rand(b, 3, 48, 64),
        "observation.state": torch.zeros(b, 6),
        "action": torch.eye(4)[[0, 1, 2, 3]],
        "task": ["go past the bed and stop at the desk"] * b,
        PRIVILEGED_PREFIX + "column_class": torch.randint(0, 11, (b, 32)).float(),
        PRIVILEGED_PREFIX + "column_range": torch.rand(b, 32) * 5 + 0.2,
        PRIVILEGED_PREFIX + "first": torch.eye(10)[[0] * b],
        PRIVILEGED_PREFIX + "final": torch.eye(10)[[4] * b],
    }
    loss, figures = policy.forward(batch)
    loss.backward()
    assert torch.isfinite(loss) and {"scan_class", "scan_range", "first", "final"} <= set(figures)
    assert all(p.grad is not None for p in policy.parameters() if p.requires_grad)


@pytest.mark.slow
def test_the_shipped_policy_makes_progress_on_held_out_arrangements_in_vln_sim():
    assert mean_progress(VLNSim(VLNSimConfig(camera_width=192, camera_height=144))) >= PROGRESS_FLOOR


@pytest.mark.slow
def test_the_shipped_policy_makes_progress_over_the_loopback_locobot_host(tmp_path):
    with HostThread(FREE_PORTS) as host:
        config = client_config(host.ports, tmp_path, camera_width=192, camera_height=144, use_depth=True)
        assert mean_progress(Locobot(config)) >= PROGRESS_FLOOR


def test_a_robot_without_depth_is_one_line_naming_the_option(tmp_path):
    for robot in (
        VLNSim(VLNSimConfig(depth=False)),
        Locobot(client_config(dict.fromkeys(("command", "observation", "rpc"), 1), tmp_path)),
    ):
        with pytest.raises(PolicyLoadError, match=r"--robot\.use_depth=true") as error:
            make_policy(PolicyArgs(), robot, TASK)
        assert "\n" not in str(error.value)


def test_obstacle_ranges_from_depth_agree_with_the_simulators_ray_hits():
    from lerobot_contrast.contrast.scene import Pose
    from lerobot_contrast.training.nav_episodes import NavSimulator
    from lerobot_contrast.training.nav_learner import NavLearner
    from lerobot_contrast.training.nav_teacher import Teacher

    learner, simulator = NavLearner(WEIGHTS), NavSimulator()
    errors = []
    for instance in FIXED[:2]:
        start = Pose.from_json(instance.goal["start"])
        simulator.world.set_scene(instance.scene.objects, start)
        truth = np.minimum(Teacher(instance).targets(start)["column_range"], 8.0)
        ranges = learner.policy.obstacle_ranges(learner.batch(simulator.observation()))[0].numpy()
        errors.append(np.abs(ranges - truth) / truth)
    # Per column the depth range is the nearest over the column's strip, the truth the ray through its centre.
    assert np.median(np.concatenate(errors)) < 0.05 and np.mean(np.concatenate(errors) < 0.2) > 0.85


def test_a_rows_scan_does_not_depend_on_its_batch():
    """Lanes decide as one lane: each lane's scanner class alone or batched with up to 17 others (a call of the
    scanner per 8 rows) is the same, its logits within 1e-5. Not to the last bit: a CPU's kernels may round a row
    otherwise in another batch size (docs/development.md)."""
    torch.set_num_threads(1)
    policy = VLNNavigatorPolicy.from_pretrained(WEIGHTS).eval()
    c = policy.config
    images = torch.rand(18, 3, c.image_height, c.image_width, generator=torch.Generator().manual_seed(0))
    with torch.no_grad():
        alone = torch.cat([policy.lane_logits(images[i : i + 1]) for i in range(18)])
        for size in range(2, 19):
            batched = policy.lane_logits(images[:size])
            assert torch.allclose(batched, alone[:size], rtol=0, atol=1e-5), f"a batch of {size} scans otherwise"
            assert torch.equal(batched.argmax(-1), alone[:size].argmax(-1))
