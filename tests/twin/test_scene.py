"""The twin's world follows the task file: a table, the objects with their colours, shapes and sizes where the scene
puts them, bins that hold cubes, the spare cube parked off the workspace; resting objects neither sink nor jitter."""

import math
from dataclasses import replace

import mujoco
import numpy as np
import pytest

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.task_file import load_task_file, task_from_dict
from lerobot_contrast.so101 import arm
from lerobot_contrast.so101.scene import COLOURS, build_spec, start_poses, table_extent
from lerobot_contrast.twin.physics import Physics
from lerobot_contrast.twin.servos import ServoBank

SCENE = Scene({"red_cube": Pose(0.25, 0.05, 0.4), "green_cube": Pose(0.33, -0.06), "blue_cube": Pose(0.38, 0.07, -1.0)})


@pytest.fixture(scope="module")
def blocks():
    return load_task_file("so101_blocks").spec


@pytest.fixture(scope="module")
def physics(blocks):
    bank = ServoBank(arm.MOTORS, arm.rest_raw(), limits=arm.raw_limits())
    return Physics(build_spec(blocks, SCENE), bank, blocks.objects)


def test_objects_have_the_task_files_colours_sizes_and_poses(blocks, physics):
    model = physics.model
    for name, obj in blocks.objects.items():
        geom = model.geom(name)
        assert tuple(geom.rgba[:3]) == pytest.approx(COLOURS[obj.attributes["colour"]])
        assert geom.type[0] == mujoco.mjtGeom.mjGEOM_BOX and geom.size == pytest.approx([0.015] * 3)  # small cubes
    poses = physics.poses()
    for name, pose in SCENE.objects.items():
        assert poses[name][:2] == pytest.approx((pose.x, pose.y))
        assert poses[name][3] == pytest.approx(pose.yaw)


def test_the_spare_cube_waits_in_the_tray_and_without_one_off_the_workspace(blocks, physics):
    x, y, z, _ = physics.poses()["yellow_cube"]
    assert blocks.workspace.tray.contains(x, y) and z == pytest.approx(0.015, abs=0.001)
    assert not any(region.contains(x, y) for region in blocks.workspace.regions.values())
    trayless = replace(blocks, workspace=replace(blocks.workspace, tray=None))
    spare = start_poses(trayless, None)["yellow_cube"]
    assert not trayless.workspace.area.contains(spare.x, spare.y)
    (x0, x1), (y0, y1) = table_extent(trayless)
    assert x0 < spare.x < x1 and y0 < spare.y < y1


def test_bins_are_walled_around_their_regions(blocks, physics):
    model = physics.model
    for name in ("left_bin", "right_bin"):
        region = blocks.workspace.regions[name]
        walls = [g for g in range(model.ngeom) if model.geom_bodyid[g] == model.body(name).id]
        assert len(walls) >= 8
        centres = physics.data.geom_xpos[walls]
        distances = np.hypot(centres[:, 0] - region.center[0], centres[:, 1] - region.center[1])
        assert np.all(distances > region.radius) and np.all(distances < region.radius + 0.01)


def test_resting_objects_neither_sink_nor_jitter_and_placed_ones_settle(physics):
    before = physics.poses()
    physics.run(1.0)
    after = physics.poses()
    for name, (x, y, z, yaw) in after.items():
        assert z == pytest.approx(0.015, abs=0.0005)
        assert math.hypot(x - before[name][0], y - before[name][1]) < 0.0005
        assert yaw == pytest.approx(before[name][3], abs=0.01)
    physics.place("red_cube", 0.30, 0.18, 0.2)  # into the left bin
    physics.run(0.5)
    x, y, z, yaw = physics.poses()["red_cube"]
    assert (x, y, z, yaw) == pytest.approx((0.30, 0.18, 0.015, 0.2), abs=0.001)
    dof = physics.model.joint("red_cube").dofadr[0]
    assert np.linalg.norm(physics.data.qvel[dof : dof + 6]) < 1e-3  # at rest


def other_task() -> dict:
    return {
        "version": 1,
        "name": "fruit_bowl",
        "workspace": {
            "units": "m",
            "bounds": {"x": [0.1, 0.4], "y": [-0.2, 0.2]},
            "regions": {"bowl": {"x": [0.25, 0.35], "y": [0.05, 0.15], "words": ["fruit bin"]}, "mat": {"center": [0.2, -0.1], "radius": 0.05}},
        },
        "objects": {
            "plum": {"colour": "purple", "shape": "ball", "size": "large"},
            "can": {"colour": "orange", "shape": "cylinder"},
            "stand": {"colour": "black", "movable": False, "at": [0.15, 0.15]},
        },
        "instances": [{"instruction": "put the purple ball in the fruit bin", "goal": {"subject": "plum", "in": "bowl"},
                       "placements": {"plum": [0.2, 0.0], "can": [0.3, -0.1]}}],
    }  # fmt: skip


def test_another_task_file_builds_another_scene():
    task = task_from_dict(other_task()).spec
    model = build_spec(task, Scene({"plum": Pose(0.2, 0.0), "can": Pose(0.3, -0.1)})).compile()
    assert model.geom("plum").type[0] == mujoco.mjtGeom.mjGEOM_SPHERE and model.geom("plum").size[0] == 0.025
    assert model.geom("can").type[0] == mujoco.mjtGeom.mjGEOM_CYLINDER
    assert tuple(model.geom("plum").rgba[:3]) == pytest.approx(COLOURS["purple"])
    assert model.body("stand").jntnum[0] == 0  # fixed: no free joint
    assert model.body("bowl").geomnum[0] >= 8  # "fruit bin" in its words: walled
    assert mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "mat") == -1  # not a bin: nothing on the table
    assert mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "red_cube") == -1


def test_a_colour_the_twin_cannot_show_is_one_line():
    data = other_task()
    data["objects"]["can"]["colour"] = "teal"
    with pytest.raises(UserError, match=r"^object 'can': the twin cannot show colour 'teal'; use one of red, "):
        build_spec(task_from_dict(data).spec)
