"""Grasping works on the twin: through joint goals alone (Goal_Position registers, as LeRobot writes them), from
inverse kinematics, the arm picks the red cube from the play area and puts it in a bin, as the true scene shows."""

import math

import pytest

from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.task_file import load_task_file
from lerobot_contrast.so101 import arm, reach
from lerobot_contrast.so101.scene import build_spec
from lerobot_contrast.twin.operator import held
from lerobot_contrast.twin.physics import Physics
from lerobot_contrast.twin.servos import ServoBank


@pytest.fixture(scope="module")
def blocks():
    return load_task_file("so101_blocks").spec


def bench(task, red: Pose) -> Physics:
    scene = Scene({"red_cube": red, "green_cube": Pose(0.22, -0.07), "blue_cube": Pose(0.21, 0.08)})
    bank = ServoBank(arm.MOTORS, arm.rest_raw(), limits=arm.raw_limits())
    physics = Physics(build_spec(task, scene), bank, task.objects)
    for servo_id in bank.ids:
        bank.memory(servo_id).write("Torque_Enable", 1)
    return physics


@pytest.mark.parametrize(
    ("red", "bin_name"), [(Pose(0.27, 0.04, 0.5), "left_bin"), (Pose(0.36, -0.02, -2.0), "right_bin")]
)
def test_the_arm_puts_the_red_cube_in_a_bin(blocks, red, bin_name):
    physics = bench(blocks, red)
    region = blocks.workspace.regions[bin_name]
    x, y, z, _ = reach.carry(physics, "red_cube", region.center)
    assert region.contains(x, y)
    assert z == pytest.approx(0.015, abs=0.002)  # on the table inside the walls, not perched on one
    others = physics.poses()
    assert others["green_cube"][:2] == pytest.approx((0.22, -0.07), abs=0.002)  # nothing else knocked about
    assert others["blue_cube"][:2] == pytest.approx((0.21, 0.08), abs=0.002)
    rest = {n: arm.to_angle(n, physics.bank.present(n)) for n in arm.MOTOR_NAMES}
    assert all(abs(rest[n] - arm.REST[n]) < math.radians(3) for n in arm.MOTOR_NAMES)  # back at rest


@pytest.mark.parametrize("yaw", [-0.78, -0.52, -0.39, -0.13, 0.13, 0.39, 0.52])
def test_a_cube_turned_any_way_is_put_down_where_asked(blocks, yaw):
    """The fixed pad comes down beside the face, not on its edge, and leaves it before rising: at these turns a pad
    that skimmed the face pressed the cube into the table or dragged it 2.8 cm on the way up."""
    physics = bench(blocks, Pose(0.34, -0.007, yaw))
    x, y, z, _ = reach.carry(physics, "red_cube", (0.30, 0.06))
    assert math.dist((x, y), (0.30, 0.06)) < 0.006 and z == pytest.approx(0.015, abs=0.002)


def test_a_cube_near_the_base_is_carried_far_out(blocks):
    """From the pose that lifts a cube next to the base, the search for the far carry pose stuck 1.5-2 mm short
    against a joint limit ("out of reach", and a person called); it now starts again from rest turned that way."""
    physics = bench(blocks, Pose(0.2028, 0.0702, 0.5105))
    physics.place("blue_cube", 0.40, 0.10, 0.0)  # out of the way
    x, y, z, _ = reach.carry(physics, "red_cube", (0.36, -0.057))
    assert math.dist((x, y), (0.36, -0.057)) < 0.006 and z == pytest.approx(0.015, abs=0.002)


def test_waypoints_grip_across_the_faces_and_lift_clear(blocks):
    physics = bench(blocks, Pose(0.25, 0.0, 0.3))
    start = {n: arm.to_angle(n, physics.bank.present(n)) for n in arm.MOTOR_NAMES}
    plan = reach.pick_and_place(physics.model, start, physics.poses()["red_cube"], 0.03, (0.3, 0.18))
    steps = {waypoint.label: waypoint for waypoint in plan}
    assert list(steps) == ["open", "descend", "close", "lift", "carry", "lower", "release", "clear", "retreat", "rest"]
    assert steps["close"].goals[arm.GRIPPER] < reach.jaw_angle(physics.model, 0.03) < steps["open"].goals[arm.GRIPPER]
    reach.follow(physics, plan[:4])
    assert physics.poses()["red_cube"][2] > 0.06  # held up in the air by the jaws
    assert physics.gripped() == {"red_cube"}  # the truth the judge reads: in the jaws


def test_a_cube_lying_on_another_is_lifted_but_not_held(blocks):
    """The judge's truth: lifted off its rest is not enough for held, it must touch the jaws (a cube the policy dropped
    onto another in a bin was counted held, and the camera's right label a mistake)."""
    physics = bench(blocks, Pose(0.30, 0.0))
    green = physics.model.joint("green_cube").qposadr[0]
    physics.data.qpos[green : green + 3] = [0.30, 0.0, 0.047]  # on top of the red cube
    physics.run(0.5)
    x, y, z, _ = physics.poses()["green_cube"]
    assert math.dist((x, y), (0.30, 0.0)) < 0.01 and z > 0.04  # resting on it, 3 cm up
    assert physics.gripped() == set()
    assert held({"green_cube": z, "red_cube": 0.015}, {"green_cube": 0.015, "red_cube": 0.015}, set()) == {}


def test_a_target_beyond_reach_is_refused_not_attempted(blocks):
    physics = bench(blocks, Pose(0.25, 0.0))
    start = {n: arm.to_angle(n, physics.bank.present(n)) for n in arm.MOTOR_NAMES}
    with pytest.raises(reach.Unreachable, match="cannot reach"):
        reach.pick_and_place(physics.model, start, physics.poses()["red_cube"], 0.03, (0.9, 0.0))
