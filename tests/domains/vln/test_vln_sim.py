"""VLN in simulation without the LoCoBot plugin: the in-process vln_sim robot drives the same apartment as the
LoCoBot host's sim backend, so a trial there ends exactly as it does over loopback."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from navigation_protocol import CAMERA, DEPTH, DISCRETE_KEYS, STATE_KEYS, one_hot

from lerobot_contrast.domains.vln import VLNTask
from lerobot_contrast.domains.vln.config_vln_sim import VLNSimConfig
from lerobot_contrast.domains.vln.vln_sim import VLNSim
from lerobot_contrast.eval import main as eval_main
from lerobot_contrast.policies.route_follower import RouteFollower
from lerobot_contrast.spine.runner import RobotRunner
from tests.policies.test_route_follower import context_for

TASK = VLNTask()


def run_episode(robot, instance):
    robot.connect()
    try:
        return RobotRunner(robot, RouteFollower(), TASK, operator=None, fps=None, max_steps=150)(context_for(instance))
    finally:
        robot.disconnect()


def test_the_robot_has_the_locobot_features_and_steps_at_once(tmp_path):
    robot = VLNSim(VLNSimConfig(camera_width=64, camera_height=48, calibration_dir=tmp_path))
    assert robot.action_features == dict.fromkeys(DISCRETE_KEYS, float)
    assert set(robot.observation_features) == {*STATE_KEYS, CAMERA, DEPTH}
    assert set(VLNSim(VLNSimConfig(depth=False)).observation_features) == {*STATE_KEYS, CAMERA}
    robot.connect()
    start = robot.get_observation()
    assert start[CAMERA].shape == (48, 64, 3) and start[CAMERA].dtype == np.uint8
    assert start[DEPTH].shape == (48, 64, 1) and start[DEPTH].dtype == np.float32 and 0 < start[DEPTH].min() < 10
    robot.send_action(one_hot("turn_left"))
    assert robot.get_observation()["odom.theta"] == pytest.approx(start["odom.theta"] + np.radians(30))
    assert robot.send_action(one_hot(None)) == one_hot(None) and not robot.stop_requested
    robot.send_action(one_hot("stop"))
    assert robot.stop_requested
    robot.disconnect()


def test_an_episode_in_process_ends_as_over_loopback(tmp_path):
    from lerobot_robot_locobot import Locobot
    from lerobot_robot_locobot.host import HostThread

    from tests.robots.locobot_helpers import FREE_PORTS, client_config

    instance = TASK.examples[1]
    here = run_episode(VLNSim(VLNSimConfig(camera=False, calibration_dir=tmp_path)), instance)
    with HostThread(FREE_PORTS) as host:
        there = run_episode(Locobot(client_config(host.ports, tmp_path)), instance)
    assert here.success and here.progress == 1.0 and here.extra["ended_by"] == "policy"
    assert (here.steps, here.path_length, here.scene_after) == (there.steps, there.path_length, there.scene_after)


BLOCKED = """
import sys
from importlib.abc import MetaPathFinder


class NoLocobot(MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] == "lerobot_robot_locobot":
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)


sys.meta_path.insert(0, NoLocobot())
from lerobot_contrast.eval import main

code = main(sys.argv[1:])
assert not any(name.startswith("lerobot_robot_locobot") for name in sys.modules)
sys.exit(code)
"""


def test_the_eval_cli_runs_vln_in_simulation_with_the_locobot_plugin_unimportable(tmp_path):
    flags = ["--task=vln_paper", "--policy.type=route_follower", "--n_instances=1", "--perturbations=[L,SB]",
             "--rerun=false", "--max_episode_steps=150", f"--output_dir={tmp_path / 'run'}"]  # fmt: skip
    done = subprocess.run([sys.executable, "-c", BLOCKED, *flags], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    records = [json.loads(line) for line in (tmp_path / "run" / "journal.jsonl").read_text().splitlines()]
    assert [r["perturbation"] for r in records] == [None, "L", "SB"]
    assert all(r["status"] == "done" and r["success"] and r["progress"] == 1.0 for r in records)
    assert json.loads((tmp_path / "run" / "config.json").read_text())["robot"]["type"] == "vln_sim"


def test_a_vln_run_without_a_policy_flag_is_labelled_with_the_learned_navigator(tmp_path):
    run = tmp_path / "run"
    flags = ["--task=vln_paper", "--n_instances=1", "--strategy=standard", "--max_episode_steps=5", "--rerun=false"]
    assert eval_main([*flags, f"--output_dir={run}"]) == 0
    assert json.loads((run / "summary.json").read_text())["settings"]["policy"] == "vln_navigator"
