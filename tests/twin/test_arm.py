"""The twin's SO-101: the installed model, LeRobot's motors, and raw steps under which LeRobot's calibrated degrees are
the model's joint angles (checked through LeRobot's own normalisation), and servos that reach and hold a pose."""

import math
import subprocess
import time
from pathlib import Path

import mujoco
import pytest
from lerobot.motors import MotorCalibration
from lerobot.robots.so_follower import SO101Follower, SO101FollowerConfig

from lerobot_contrast.domains.task_file import load_task_file
from lerobot_contrast.so101 import arm
from lerobot_contrast.so101.scene import build_spec
from lerobot_contrast.twin.physics import Physics
from lerobot_contrast.twin.servos import ServoBank

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def follower_bus():
    """LeRobot's own SO-101 bus (never connected), calibrated as the twin's calibration file says."""
    robot = SO101Follower(SO101FollowerConfig(port="/dev/null", id="twin_test"))
    robot.bus.calibration = {
        name: MotorCalibration(id=servo_id, drive_mode=0, homing_offset=0, range_min=low, range_max=high)
        for name, (servo_id, _), (low, high) in zip(
            arm.MOTORS, arm.MOTORS.values(), arm.raw_limits().values(), strict=True
        )
    }
    return robot.bus


def test_the_model_comes_from_the_installed_package_not_this_repository():
    path = arm.model_path()
    assert path.is_file() and path.name == "so101_new_calib.xml"
    assert "site-packages" in path.parts
    tracked = subprocess.run(
        ["git", "ls-files", "*so101_new_calib*", "*.stl"], cwd=REPO, capture_output=True, text=True
    )
    assert tracked.stdout == ""
    spec = mujoco.MjSpec.from_file(str(path))
    assert {j.name for j in spec.joints} == set(arm.MOTOR_NAMES)


def test_motors_are_lerobots_so101_motors(follower_bus):
    assert {name: (m.id, m.model) for name, m in follower_bus.motors.items()} == arm.MOTORS


@pytest.mark.parametrize("name", arm.MOTOR_NAMES)
def test_lerobot_reads_the_models_joint_angle(follower_bus, name):
    """LeRobot's normalisation of the raw position at each angle gives that angle in degrees (the gripper: its joint
    range as 0-100), and LeRobot's goal for that reading lands on the same raw step."""
    low, high = arm.joint_ranges()[name]
    servo_id = arm.MOTORS[name][0]
    for angle in (low, low / 2, 0.0, 0.3, high / 2, high):
        raw = round(arm.to_raw(name, angle))
        read = follower_bus._normalize({servo_id: raw})[servo_id]
        assert read == pytest.approx(arm.to_lerobot(name, angle), abs=0.1)
        assert abs(follower_bus._unnormalize({servo_id: read})[servo_id] - raw) <= 1
    if name == arm.GRIPPER:
        assert follower_bus._normalize({servo_id: arm.raw_limits()[name][0]})[servo_id] == pytest.approx(0.0)
        assert follower_bus._normalize({servo_id: arm.raw_limits()[name][1]})[servo_id] == pytest.approx(100.0)


def test_raw_limits_stay_on_the_encoder_and_inside_the_joints():
    for name, (low, high) in arm.raw_limits().items():
        assert 0 <= low < high <= 4095
        if name != arm.FULL_TURN:
            joint_low, joint_high = arm.joint_ranges()[name]
            assert joint_low - 1e-3 <= arm.to_angle(name, low) and arm.to_angle(name, high) <= joint_high + 1e-3
        assert low <= arm.rest_raw()[name] <= high


def test_mapping_round_trips():
    for name in arm.MOTOR_NAMES:
        for angle in (-0.7, 0.0, 0.25, 1.1):
            assert arm.to_angle(name, arm.to_raw(name, angle)) == pytest.approx(angle)
            assert arm.from_lerobot(name, arm.to_lerobot(name, angle)) == pytest.approx(angle)


@pytest.fixture(scope="module")
def blocks():
    return load_task_file("so101_blocks").spec


def test_rest_pose_is_clear_of_the_table_and_of_itself(blocks):
    model = build_spec(blocks).compile()
    data = mujoco.MjData(model)
    for name, angle in arm.REST.items():
        data.qpos[model.joint(name).qposadr[0]] = angle
    mujoco.mj_forward(model, data)
    arm_bodies = {model.body(name).id for name in ("shoulder", "upper_arm", "lower_arm", "wrist", "gripper")}
    touching = [c for c in data.contact[: data.ncon] if model.geom_bodyid[c.geom1] in arm_bodies]
    assert not touching
    assert data.site("gripperframe").xpos[2] > 0.06  # above the cubes, out of the way


def test_servos_reach_a_commanded_pose_and_hold_it_under_gravity(blocks):
    bank = ServoBank(arm.MOTORS, arm.rest_raw(), limits=arm.raw_limits())
    physics = Physics(build_spec(blocks), bank, blocks.objects)
    goal = {"shoulder_pan": 25.0, "shoulder_lift": -20.0, "elbow_flex": 35.0, "wrist_flex": 50.0, "wrist_roll": -30.0,
            "gripper": 60.0}  # fmt: skip
    for name, value in goal.items():
        memory = bank.memory(arm.MOTORS[name][0])
        memory.write("Torque_Enable", 1)
        memory.write("Goal_Position", round(arm.to_raw(name, arm.from_lerobot(name, value))))
    physics.run(0.1)
    moved = {n: arm.to_lerobot(n, arm.to_angle(n, bank.present(n))) for n in goal}
    assert any(abs(moved[n] - goal[n]) > 5 for n in goal)  # servos move at finite speed
    physics.run(0.9)
    for name, value in goal.items():
        joint = physics.data.qpos[physics.model.joint(name).qposadr[0]]
        assert arm.to_lerobot(name, joint) == pytest.approx(value, abs=1.0)  # the model's joint, as LeRobot reads it
        assert arm.to_lerobot(name, arm.to_angle(name, bank.present(name))) == pytest.approx(value, abs=1.0)
    assert math.isfinite(physics.poses()["red_cube"][0])


def test_joint_goals_become_lerobots_action():
    action = arm.lerobot_action({"shoulder_pan": math.radians(30), arm.GRIPPER: arm.joint_ranges()[arm.GRIPPER][1]})
    assert action == pytest.approx({"shoulder_pan.pos": 30.0, "gripper.pos": 100.0})


@pytest.mark.realtime
def test_the_real_time_thread_keeps_to_the_clock_and_says_why_it_stops(blocks, capsys):
    bank = ServoBank(arm.MOTORS, arm.rest_raw(), limits=arm.raw_limits())
    physics = Physics(build_spec(blocks), bank, blocks.objects)
    physics.start()
    try:
        time.sleep(0.5)
        simulated = physics.read(lambda model, data: data.time)
        assert 0.1 < simulated < 0.6  # never ahead of the wall clock; behind only as far as a busy machine makes it

        def unplugged(dt):
            raise OSError("the bus process is gone")

        bank.step = unplugged
        time.sleep(0.2)
    finally:
        physics.stop()
    assert physics.error == "twin physics stopped: the bus process is gone"
    assert capsys.readouterr().err == "twin physics stopped: the bus process is gone\n"
