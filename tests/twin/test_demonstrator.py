"""The scripted demonstrator (`--teleop.type=so101_demo`): it understands every so101_blocks instruction, places the
cubes anew (seeded) when it connects and at each reset period, and hands out joint goals in LeRobot's degrees
(`lerobot-record` with it on the twin: test_act_loop.py)."""

import json
import math
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest
from lerobot_teleoperator_so101_demo import SO101Demo, SO101DemoConfig
from lerobot_teleoperator_so101_demo import so101_demo as demo_module

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.domains.task_file import load_task_file
from lerobot_contrast.ports import free_port
from lerobot_contrast.so101 import arm, plan
from lerobot_contrast.so101.scene import build_spec
from lerobot_contrast.twin.physics import Physics
from lerobot_contrast.twin.placement import PlacementServer
from lerobot_contrast.twin.servos import ServoBank

INSTRUCTION = "put the red cube in the left bin"


@pytest.fixture(scope="module")
def task():
    return load_task_file("so101_blocks")


@pytest.fixture(scope="module")
def placement(task):
    bank = ServoBank(arm.MOTORS, arm.rest_raw(), limits=arm.raw_limits())
    server = PlacementServer(Physics(build_spec(task.spec), bank, task.spec.objects), task.spec, port=free_port())
    server.start()
    yield server
    server.stop()


@pytest.mark.parametrize(
    ("instruction", "goal"),
    [
        ("Put the red cube in the left bin.", {"subject": "red_cube", "in": "left_bin"}),
        ("pick up the blue cube and put it in the bin on the right", {"subject": "blue_cube", "in": "right_bin"}),
        ("move the green cube beside the red cube", {"subject": "green_cube", "near": "red_cube", "within": 0.05}),
    ],
)
def test_instructions_are_read_with_the_task_files_templates(task, instruction, goal):
    assert plan.goal_of(task, instruction) == goal


def test_an_instruction_the_task_cannot_say_is_one_line(task):
    with pytest.raises(UserError, match=r"^the instruction 'stack the cubes' is none of task so101_blocks's") as error:
        plan.goal_of(task, "stack the cubes")
    assert "\n" not in str(error.value)


def test_placements_are_seeded_apart_and_in_the_play_area(task):
    spec = task.spec
    first = plan.placement(spec, seed=3, episode=0)
    assert first == plan.placement(spec, seed=3, episode=0)
    assert first != plan.placement(spec, seed=3, episode=1) != plan.placement(spec, seed=4, episode=0)
    assert set(first) == set(spec.placed)  # the spare cube stays off the table
    area = spec.workspace.regions["play_area"]
    for name, (x, y, _) in first.items():
        assert area.contains(x, y)
        others = [(ox, oy) for other, (ox, oy, _) in first.items() if other != name]
        assert all(math.dist((x, y), o) >= spec.workspace.min_spacing for o in others)


def test_next_to_targets_lie_beside_the_base_within_the_goal(task):
    poses = {"red_cube": (0.3, 0.0, 0.015, 0.0), "green_cube": (0.25, 0.05, 0.015, 0.0),
             "blue_cube": (0.36, -0.08, 0.015, 0.0)}  # fmt: skip
    goal = plan.goal_of(task, "put the green cube next to the red cube")
    spots = plan.targets(goal, poses, task.spec)
    assert spots and all(0.03 < math.dist(spot, (0.3, 0.0)) <= goal["within"] for spot in spots)
    assert all(math.dist(spot, (0.36, -0.08)) >= task.spec.workspace.min_spacing for spot in spots)
    poses["red_cube"] = (0.27, 0.075, 0.015, 0.0)  # beside the left bin: no spot on its wall
    bin_ = task.spec.workspace.regions["left_bin"]
    spots = plan.targets(goal, poses, task.spec)
    assert spots and all(math.dist(spot, bin_.center) > bin_.radius + 0.03 for spot in spots)
    poses["red_cube"] = (0.435, 0.0, 0.015, 0.0)  # at the workspace's far edge: not beside it past the edge
    (_, x_max), _ = task.spec.workspace.area.box
    spots = plan.targets(goal, poses, task.spec)
    assert len(spots) == 3 and all(spot[0] <= x_max - 0.015 for spot in spots)


def test_a_cube_goes_into_a_bin_clear_of_the_one_already_there(task):
    goal = plan.goal_of(task, "put the red cube in the right bin")
    bin_ = task.spec.workspace.regions["right_bin"]
    poses = {"red_cube": (0.3, 0.05, 0.015, 0.0), "green_cube": (0.36, 0.1, 0.015, 0.0),
             "blue_cube": (*bin_.middle, 0.015, 0.0)}  # fmt: skip
    spot = plan.targets(goal, poses, task.spec)[0]
    assert bin_.contains(*spot) and math.dist(spot, bin_.middle) >= 0.03  # beside the blue cube, not onto it
    poses["blue_cube"] = (bin_.middle[0] + 0.03, bin_.middle[1], 0.015, 0.0)  # at one side: the other side
    spot = plan.targets(goal, poses, task.spec)[0]
    assert bin_.contains(*spot) and math.dist(spot, poses["blue_cube"][:2]) > task.spec.workspace.min_spacing - 1e-9
    poses["blue_cube"] = (0.3, -0.05, 0.015, 0.0)  # an empty bin: its middle
    assert plan.targets(goal, poses, task.spec)[0] == pytest.approx(bin_.middle)


def where(server, names) -> list[float]:
    """The objects' x, y on the twin, in the order of `names`."""
    objects = server.answer(b'{"cmd": "scene"}')["objects"]
    return [value for name in names for value in objects[name][:2]]


def planned(spec, seed: int, episode: int) -> tuple[list[str], list[float]]:
    placed = plan.placement(spec, seed, episode)
    return list(placed), [value for x, y, _ in placed.values() for value in (x, y)]


def calls_until(teleop, clock: list[float], until: float) -> dict[str, float]:
    """lerobot-record's loop: get_action at 30 Hz until the clock reads `until`; the last action."""
    while clock[0] < until:
        clock[0] += 1 / 30
        action = teleop.get_action()
    return action


def test_the_cubes_are_placed_anew_at_each_reset_and_the_plan_restarts_after_the_save(placement, monkeypatch):
    clock = [100.0]
    monkeypatch.setattr(demo_module.time, "monotonic", lambda: clock[0])
    config = SO101DemoConfig(placement=placement.address, instruction=INSTRUCTION, episode_time_s=20, seed=7)
    teleop = SO101Demo(config)
    teleop.connect()
    names, first = planned(placement.task, 7, 0)
    assert where(placement, names) == pytest.approx(first, abs=1e-3)
    action = teleop.get_action()
    assert set(action) == set(teleop.action_features) == {f"{name}.pos" for name in arm.MOTOR_NAMES}
    assert 5 < teleop.schedule_s < 20  # the pick-and-place fits the episode
    opened = calls_until(teleop, clock, 101.0)  # on the way in: the jaws open
    assert opened["gripper.pos"] > arm.to_lerobot("gripper", arm.REST["gripper"]) + 10
    # The reset period: at rest, the cubes placed for the next episode.
    assert calls_until(teleop, clock, 120.5) == pytest.approx(
        {f"{n}.pos": arm.to_lerobot(n, arm.REST[n]) for n in arm.MOTOR_NAMES}
    )
    names, second = planned(placement.task, 7, 1)
    assert where(placement, names) == pytest.approx(second, abs=1e-3)
    clock[0] += 2.0 - 1 / 30  # lerobot-record saved the episode: the next one begins, planned on the new scene
    assert calls_until(teleop, clock, 123.5)["gripper.pos"] == pytest.approx(opened["gripper.pos"], abs=0.5)
    assert teleop.episode == 2
    teleop.disconnect()


def test_a_twin_that_does_not_answer_is_one_line():
    config = SO101DemoConfig(placement=f"tcp://127.0.0.1:{free_port()}", instruction=INSTRUCTION)
    with pytest.raises(UserError, match=r"^so101_demo: no twin answers on tcp://127.0.0.1:\d+ within 5 s; start it"):
        SO101Demo(config).connect()


def test_the_recording_script_answers_a_bad_instruction_in_one_line(tmp_path):
    script = "scripts/train/record_so101_demos.py"
    done = subprocess.run([sys.executable, script, f"--output={tmp_path / 'd'}", "--task=juggle"],
                          capture_output=True, text=True, timeout=60)  # fmt: skip
    assert done.returncode == 2 and done.stderr.startswith("error: --task: the instruction 'juggle' is none of")
    assert done.stderr.count("\n") == 1


def test_the_recorder_fails_when_lerobot_record_exits_0_short_of_its_episodes(tmp_path, monkeypatch):
    from tests.study_scripts import load_script

    record = load_script("record_so101_demos")
    args = record.parse_args([f"--output={tmp_path / 'demos'}", "--episodes=3", "--tries=2"])
    runs = []

    def one_episode_then_stop(command):  # lerobot-record saving 1 episode each run and exiting 0
        runs.append(command)
        meta = tmp_path / "demos" / "meta"
        meta.mkdir(parents=True, exist_ok=True)
        (meta / "info.json").write_text(json.dumps({"total_episodes": len(runs)}))
        return subprocess.CompletedProcess(command, 0)

    monkeypatch.setattr(record.subprocess, "run", one_episode_then_stop)
    twin = SimpleNamespace(robot_flags="--robot.type=so101_follower", placement="tcp://127.0.0.1:1")
    why = record.record(args, twin, tmp_path / "demos", 0, 3)
    assert why == "lerobot-record saved 2 of the 3 episodes of demos in 2 runs" and len(runs) == 2


def test_as_an_evaluator_policy_it_carries_out_each_trials_goal_on_the_true_scene(placement, monkeypatch):
    from lerobot.robots.so_follower import SO101Follower, SO101FollowerConfig

    from lerobot_contrast import PolicyArgs, TrialContext, make_policy
    from lerobot_contrast.twin import demonstrator as policy_module

    clock = [50.0]  # the robot's clock (clock/robot_clock.py), moved by hand
    monkeypatch.setattr(policy_module, "robot_clock", lambda: SimpleNamespace(now=lambda: clock[0]))
    robot = SO101Follower(SO101FollowerConfig(port="unused", id="demo"))
    task = load_task_file("so101_red_left")
    demonstrator = make_policy(
        PolicyArgs(type="so101_demonstrator", options={"placement": placement.address}), robot, task
    )
    base = task.sample(1, np.random.default_rng(0))[0]
    flipped = task.perturbations.get("LB2").apply(base, np.random.default_rng(0))  # "... in the right bin"
    for name, pose in base.scene.objects.items():  # the operator staged the trial's scene
        placement.answer(json.dumps({"cmd": "place", "object": name, "x": pose.x, "y": pose.y}).encode())
    pans = []
    for instance in (base, flipped):
        demonstrator.reset(TrialContext(0, instance, base, base.scene, 0.0, "reset", np.random.default_rng(0), 1))
        actions = [demonstrator.act({}) for clock[0] in np.arange(50.0, 70.0, 0.5)]
        assert set(actions[0]) == {f"{name}.pos" for name in arm.MOTOR_NAMES}
        pans.append(min(a["shoulder_pan.pos"] for a in actions) + max(a["shoulder_pan.pos"] for a in actions))
    # The same red cube, put in the left bin (y > 0), then in the right one: the arm swings the other way to drop it
    # (LeRobot's shoulder_pan degrees grow towards the arm's right).
    assert pans[1] > pans[0] + 20


def test_as_a_policy_it_refuses_another_robot_in_one_line():
    from lerobot_contrast import PolicyArgs, make_policy
    from lerobot_contrast.domains.language_table.config_language_table_sim import LanguageTableSimConfig
    from lerobot_contrast.domains.language_table.language_table_sim import LanguageTableSim
    from lerobot_contrast.policies import PolicyError

    with pytest.raises(PolicyError, match=r"^--policy.type=so101_demonstrator drives an SO-101 \(--robot.type="):
        make_policy(PolicyArgs(type="so101_demonstrator"), LanguageTableSim(LanguageTableSimConfig()),
                    load_task_file("so101_red_left"))  # fmt: skip
