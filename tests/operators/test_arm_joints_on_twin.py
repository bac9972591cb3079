"""On the twin with every joint 3 degrees off the arm's model (--joint_offset_deg=3): the arm measures its joints
before its first trial and then puts a cube within a centimetre of its target with nobody called; a resumed run
recalls the measurement instead of moving through the views again; a camera that never shows the ball stops the
measurement with one line saying what to do."""

import numpy as np
import pytest

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.operators.arm import joints as arm_joints
from lerobot_contrast.operators.arm.memory import ArmMemory
from lerobot_contrast.twin.arm_session import connected_arm
from lerobot_contrast.twin.launch import running_twin
from lerobot_contrast.twin.placement_client import PlacementClient
from lerobot_contrast.twin.table_calibration import calibrate_table
from tests.operators.test_arm_on_twin import trial

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    work = tmp_path_factory.mktemp("joints")
    with running_twin("--task=so101_blocks", "--clock=sim", "--joint_offset_deg=3") as twin:
        yield twin, calibrate_table(twin, "so101_blocks", work / "table.calibration.json")


def said(operator) -> str:
    return operator.person.console.file.getvalue()


def test_measured_joints_put_a_cube_on_its_target_and_a_resumed_run_recalls_them(bench, tmp_path):
    twin, table = bench
    placement = PlacementClient(twin.placement)
    start = {"red_cube": (0.25, -0.08), "green_cube": (0.33, 0.09), "blue_cube": (0.40, -0.02)}
    for name, (x, y) in start.items():
        placement.place(name, x, y, 0.0)
    current = Scene({name: Pose(x, y) for name, (x, y) in start.items()})
    wanted = Scene({**current.objects, "red_cube": Pose(0.30, 0.02)})
    robot, operator = connected_arm(twin, table, "so101_blocks")
    operator.memory = ArmMemory(lambda: tmp_path)
    try:
        assert operator.stage(trial(0, wanted, current)).action == "ready"
        red = placement.poses()["red_cube"]
        assert np.hypot(red[0] - 0.30, red[1] - 0.02) < 0.01, operator.attempts  # the twin's truth
        assert operator.calls == 0
        assert "measuring the arm's joints" in said(operator)
        kept = arm_joints.recall(tmp_path)
        assert kept is not None and kept.error_px < 1.5
        assert all(2.0 < abs(np.degrees(value)) < 4.0 for name, value in kept.offsets.items() if name != "wrist_roll")
    finally:
        robot.disconnect()
    robot, resumed = connected_arm(twin, table, "so101_blocks")
    resumed.memory = ArmMemory(lambda: tmp_path)
    try:
        assert resumed.stage(trial(1, current, wanted)).action == "ready"
        assert "measuring the arm's joints" not in said(resumed) and resumed.motion.offsets == kept.offsets
        red = placement.poses()["red_cube"]
        assert np.hypot(red[0] - 0.25, red[1] + 0.08) < 0.01
    finally:
        robot.disconnect()


def test_a_camera_that_never_shows_the_ball_stops_the_measurement_in_one_line(bench):
    twin, table = bench
    robot, operator = connected_arm(twin, table, "so101_blocks")
    blank = np.zeros((480, 640, 3), np.uint8)  # a camera looking at nothing of the ball's colour
    try:
        with pytest.raises(UserError, match=r"saw the purple ball on the fixed jaw whole in 0 views, 10 are needed"):
            arm_joints.measure(operator.motion, lambda: blank, operator.camera.calibration)
    finally:
        robot.disconnect()
