"""--arm.measure_joints: the arm's joint offsets fitted from where a camera sees the ball on its fixed jaw put the
jaws where they really are, wherever the ball was stuck on; and the flag refuses a table with an object of the
ball's colour."""

import math
from types import SimpleNamespace

import mujoco
import numpy as np
import pytest

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.domains import load_task
from lerobot_contrast.operators.arm.args import ArmArgs
from lerobot_contrast.operators.arm.setup import arm_operator
from lerobot_contrast.so101 import arm, marker, plan, reach

CAMERA = np.array([0.95, 0.45, 0.65])  # in front of the arm and to its left, above the table, as the twin's


def pinhole(points: np.ndarray) -> np.ndarray:
    """A 640x480 camera at CAMERA looking at the workspace's middle."""
    forward = np.array([0.30, 0.0, 0.0]) - CAMERA
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    rotation = np.stack([right, np.cross(forward, right), forward])
    camera = (np.asarray(points) - CAMERA) @ rotation.T
    return 640 * camera[:, :2] / camera[:, 2:] + [319.5, 239.5]


def jaws_off(model, offsets: dict, fitted: dict) -> list[float]:
    """How far (m) the point between the jaws lands from where the model puts it, over the workspace, with the joints
    truly `offsets` off and the arm moving through `fitted`."""
    data, point, misses = mujoco.MjData(model), reach.grasp_point(model, 0.03), []
    for x in (0.2, 0.3, 0.4):
        for y in (-0.2, 0.0, 0.2):
            goals = reach.solve(model, point, np.array([x, y, 0.015]), None, dict(arm.REST))
            true = {name: goals[name] - fitted.get(name, 0.0) + offsets[name] for name in reach.ARM_JOINTS}
            misses.append(float(np.linalg.norm(marker.ball_position(model, data, true, point) - [x, y, 0.015])))
    return misses


def test_the_fitted_offsets_put_the_jaws_where_they_are_with_the_ball_stuck_a_little_off():
    model = plan.arm_model(load_task("so101_blocks").spec)
    data = mujoco.MjData(model)
    offsets = dict(zip(reach.ARM_JOINTS, np.radians([3.0, -3.0, 3.0, -2.0, 3.0]), strict=True))
    stuck = np.asarray(marker.AT) + [0.003, -0.002, 0.002]  # not quite where the docs say
    readings = marker.poses(model, arm.REST, CAMERA)
    seen = pinhole([marker.ball_position(model, data, {n: r[n] + offsets[n] for n in r}, stuck) for r in readings])
    seen += np.random.default_rng(0).normal(0.0, 0.4, seen.shape)  # the centroid's noise, in pixels
    fitted = marker.fit(model, pinhole, readings, seen)
    assert fitted.error_px < 1.0 and fitted.views == len(readings) >= 20
    assert max(jaws_off(model, offsets, {})) > 0.02  # unmeasured, the jaws miss by centimetres
    assert max(jaws_off(model, offsets, dict(fitted.offsets))) < 0.003  # measured, by millimetres
    assert math.degrees(abs(fitted.offsets["shoulder_pan"] - offsets["shoulder_pan"])) < 0.3
    restored = marker.JointFit.from_json(fitted.to_json())
    assert max(jaws_off(model, offsets, dict(restored.offsets))) < 0.003  # as kept in the run directory


def test_a_table_with_an_object_of_the_balls_colour_is_refused_while_the_joints_are_measured():
    robot = SimpleNamespace(robot_type="so_follower", name="so101_follower")
    bench = SimpleNamespace(calibration=object(), geometry=SimpleNamespace(colours={"grape": "purple"}, size=0.03))
    task = load_task("so101_blocks")
    with pytest.raises(UserError, match="purple ball on the arm's jaw, and grape has its colour.*measure_joints=false"):
        arm_operator(ArmArgs(), robot, task, bench, None, lambda: None, 0)
    assert arm_operator(ArmArgs(measure_joints=False), robot, task, bench, None, lambda: None, 0) is not None
