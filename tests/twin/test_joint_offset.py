"""--joint_offset_deg: each joint of the twin sits its calibration error away from what its servo reports, as a real
arm whose calibration is a few degrees off the kinematic model's zero."""

import math

import numpy as np
import pytest

from lerobot_contrast.domains.task_file import load_task_file
from lerobot_contrast.so101 import arm
from lerobot_contrast.so101.scene import build_spec
from lerobot_contrast.twin.physics import Physics
from lerobot_contrast.twin.process import TwinConfig, joint_offsets
from lerobot_contrast.twin.servos import ServoBank


def test_each_joint_is_off_by_the_offset_with_a_seeded_sign():
    offsets = joint_offsets(arm.MOTOR_NAMES, 3.0, seed=0)
    assert all(abs(abs(value) - math.radians(3.0)) < 1e-12 for value in offsets.values())
    assert offsets == joint_offsets(arm.MOTOR_NAMES, 3.0, seed=0)
    assert len({math.copysign(1, v) for v in offsets.values()}) == 2  # some up, some down
    with pytest.raises(Exception, match="--joint_offset_deg=12: give degrees from 0 to 10"):
        TwinConfig(joint_offset_deg=12).check()


def test_the_servo_reports_the_calibrated_angle_while_the_joint_sits_off_it():
    blocks = load_task_file("so101_blocks").spec
    offsets = joint_offsets(arm.MOTOR_NAMES, 3.0, seed=1)
    bank = ServoBank(arm.MOTORS, arm.rest_raw(), limits=arm.raw_limits())
    physics = Physics(build_spec(blocks), bank, blocks.objects, offsets)
    goal = {"shoulder_pan": 20.0, "shoulder_lift": -30.0, "elbow_flex": 40.0, "wrist_flex": 45.0}
    for name, value in goal.items():
        memory = bank.memory(arm.MOTORS[name][0])
        memory.write("Torque_Enable", 1)
        memory.write("Goal_Position", round(arm.to_raw(name, arm.from_lerobot(name, value))))
    physics.run(1.0)
    for name, value in goal.items():
        reported = arm.to_lerobot(name, arm.to_angle(name, bank.present(name)))
        true = physics.data.qpos[physics.model.joint(name).qposadr[0]]
        assert reported == pytest.approx(value, abs=1.0)  # the servo says it reached the goal
        assert np.degrees(true) - reported == pytest.approx(np.degrees(offsets[name]), abs=0.2)
