"""The arm as its own operator on the twin, as on the bench: LeRobot's so101_follower and zmq camera, the table
calibrated from the printed board, the twin on its simulated clock. The camera locates a cube in a bin and one held
in the gripper; the arm brings the spare cube in from the tray and takes it back with nobody called, and killed
while it carries the spare, stages it again from where it fell with nothing lost; a session runs with the twin's
placement socket closed (nothing reads the truth) and, killed while the arm stages, resumes with nothing lost and
nothing counted twice."""

import json
import shlex
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from lerobot_contrast.domains import load_task
from lerobot_contrast.twin.arm_session import connected_arm
from lerobot_contrast.twin.launch import running_twin
from lerobot_contrast.twin.placement_client import PlacementClient, TwinError
from lerobot_contrast.twin.table_calibration import calibrate_table
from tests.twin.test_eval_on_twin import save_so101_act

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    work = tmp_path_factory.mktemp("arm")
    with running_twin("--task=so101_blocks", "--clock=sim") as twin:
        yield twin, calibrate_table(twin, "so101_blocks", work / "table.calibration.json"), work


def test_the_camera_sees_a_cube_in_a_bin_and_one_held_in_the_gripper(bench):
    from lerobot_contrast.so101 import reach

    twin, table, _ = bench
    placement = PlacementClient(twin.placement)
    placement.place("red_cube", 0.30, 0.18, 0.3)  # inside the left bin
    placement.place("blue_cube", 0.28, -0.05, 0.0)
    robot, operator = connected_arm(twin, table, "so101_blocks")
    try:
        view = operator._look()
        red = view.seen["red_cube"]
        assert np.hypot(red.x - 0.30, red.y - 0.18) < 0.015 and not red.held
        blue = view.seen["blue_cube"]
        steps = reach.pick_and_place(operator.motion.model, operator.motion.joints(), blue.pose(), 0.03, (0.3, 0.0))
        operator.motion.follow(steps[:4])  # open, descend, close, lift: the cube in the jaws, 10 cm up
        held = operator._look()
        truth = placement.poses()["blue_cube"]
        assert truth[2] > 0.05  # the twin's truth: it is up in the jaws
        assert held.seen["blue_cube"].held
        assert np.hypot(held.seen["blue_cube"].x - truth[0], held.seen["blue_cube"].y - truth[1]) < 0.03
        operator.motion.open_and_withdraw()
    finally:
        robot.disconnect()


def trial(index: int, scene, current):
    from lerobot_contrast.contrast.instance import Instance
    from lerobot_contrast.contrast.trial import TrialContext

    goal = {"predicate": {"subject": "red_cube", "near": "green_cube", "within": 0.05}}
    instance = Instance(f"tray-{index}", "next_to", "put the red cube next to the green cube", scene, goal, "tray")
    return TrialContext(index, instance, instance, current, 0.21, "in_place", np.random.default_rng(index), 2)


def test_the_arm_brings_the_spare_in_from_the_tray_and_takes_it_back_with_no_person(bench):
    from lerobot_contrast.contrast.scene import Pose, Scene

    twin, table, _ = bench
    placement = PlacementClient(twin.placement)
    tray = load_task("so101_blocks").spec.workspace.tray
    for name, (x, y) in {"red_cube": (0.26, 0.06), "green_cube": (0.32, -0.04), "blue_cube": (0.39, 0.07)}.items():
        placement.place(name, x, y, 0.0)
    placement.place("yellow_cube", *tray.middle, 0.0)
    without = Scene({name: Pose(*placement.poses()[name][:2]) for name in ("red_cube", "green_cube", "blue_cube")})
    with_spare = without.with_object("yellow_cube", Pose(0.36, -0.07))
    robot, operator = connected_arm(twin, table, "so101_blocks")
    try:
        assert operator.stage(trial(0, with_spare, without)).action == "ready"
        brought = placement.poses()["yellow_cube"]
        assert np.hypot(brought[0] - 0.36, brought[1] + 0.07) < 0.02  # on its target, from the tray
        picked = operator.attempts[0]  # what the journal's staging record says the arm did
        assert picked["object"] == "yellow_cube" and tray.contains(*picked["from"]) and not picked["held"]
        assert np.hypot(picked["landed"][0] - brought[0], picked["landed"][1] - brought[1]) < 0.01
        assert operator.stage(trial(1, without, with_spare)).action == "ready"
        back = placement.poses()["yellow_cube"]
        assert tray.contains(back[0], back[1]) and back[2] < 0.03  # put down in the tray
        assert operator.calls == 0  # nobody was rung
        assert "yellow_cube" not in operator._look().scene(without).objects  # waiting in the tray, off the workspace
    finally:
        robot.disconnect()


# Stages trial 0 (the spare brought in from the tray) in a process of its own, keeping what it spends in RUN_DIR.
STAGE_THE_SPARE = """
import json, sys, types
from pathlib import Path
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.operators.arm.memory import ArmMemory
from lerobot_contrast.twin.arm_session import connected_arm
from tests.operators.test_arm_on_twin import trial
flags, table, run_dir, scene = sys.argv[1:]
without = Scene({name: Pose(x, y) for name, (x, y) in json.loads(scene).items()})
robot, operator = connected_arm(types.SimpleNamespace(robot_flags=flags), Path(table), "so101_blocks")
operator.memory = ArmMemory(lambda: Path(run_dir))
staged = operator.stage(trial(0, without.with_object("yellow_cube", Pose(0.36, -0.07)), without))
print(json.dumps({"action": staged.action, "robot_s": staged.robot_s, "calls": operator.calls}))
robot.disconnect()
"""


def test_killed_while_carrying_the_spare_the_arm_stages_it_again_with_nothing_lost(bench, tmp_path):
    twin, table, _ = bench
    placement = PlacementClient(twin.placement)
    tray = load_task("so101_blocks").spec.workspace.tray
    scene = {"red_cube": (0.26, 0.06), "green_cube": (0.32, -0.04), "blue_cube": (0.39, 0.07)}
    for name, (x, y) in scene.items():
        placement.place(name, x, y, 0.0)
    placement.place("yellow_cube", *tray.middle, 0.0)
    command = [sys.executable, "-c", STAGE_THE_SPARE, twin.robot_flags, str(table), str(tmp_path), json.dumps(scene)]
    child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 240
    while placement.poses()["yellow_cube"][2] < 0.05 and time.monotonic() < deadline and child.poll() is None:
        time.sleep(0.05)
    assert placement.poses()["yellow_cube"][2] > 0.05, child.communicate()[1][-2000:]  # in the jaws, carried
    child.send_signal(signal.SIGKILL)
    child.wait()
    kept = json.loads((tmp_path / "arm_staging.json").read_text())
    assert kept["trial"] == 0 and kept["spent"]["robot_s"] > 3  # the withdraw and the way to the tray, kept
    again = subprocess.run(command, capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr[-2000:]
    staged = json.loads(again.stdout.splitlines()[-1])
    assert staged["action"] == "ready" and staged["calls"] == 0  # from where it fell, by the arm alone
    assert staged["robot_s"] > kept["spent"]["robot_s"]  # the killed session's seconds counted in
    brought = placement.poses()["yellow_cube"]
    assert np.hypot(brought[0] - 0.36, brought[1] + 0.07) < 0.02 and brought[2] < 0.03


def eval_command(twin, table, run_dir, policy, *flags):
    return [sys.executable, "-m", "lerobot_contrast.eval", "--task=so101_blocks", *shlex.split(twin.robot_flags),
            "--operator=arm", f"--policy.path={policy}", "--policy.device=cpu", "--strategy=contrast",
            "--n_instances=1", "--perturbations=L", "--max_episode_s=1", "--fps=10", "--rerun=false",
            f"--staging.calibration={table}", "--staging.viewer=none", f"--output_dir={run_dir}", *flags]  # fmt: skip


def test_with_the_placement_socket_closed_a_run_killed_mid_staging_resumes_with_nothing_lost(bench, tmp_path):
    twin, table, work = bench
    policy = save_so101_act(tmp_path / "act")
    assert PlacementClient(twin.placement).ask({"cmd": "close"}) == {"ok": True, "closed": True}
    with pytest.raises(TwinError):
        PlacementClient(twin.placement, timeout_s=1.0).ask({"cmd": "scene"})
    run_dir = tmp_path / "run"
    child = subprocess.Popen(eval_command(twin, table, run_dir, policy), stdin=subprocess.PIPE,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
    memory = run_dir / "arm_staging.json"
    deadline = time.monotonic() + 240
    while not memory.is_file() and time.monotonic() < deadline and child.poll() is None:
        time.sleep(0.5)
    child.send_signal(signal.SIGKILL)  # mid-staging: the first object placed, the rest still to do
    child.wait()
    kept = json.loads(memory.read_text())
    assert kept["trial"] == 0 and kept["spent"]["robot_s"] > 0
    assert not (run_dir / "journal.jsonl").is_file() or not (run_dir / "journal.jsonl").read_text().strip()
    resume = eval_command(twin, table, run_dir, policy, "--resume=true")
    done = subprocess.run(resume, input="\n" * 40, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    records = [json.loads(line) for line in (run_dir / "journal.jsonl").read_text().splitlines()]
    assert [r["index"] for r in records] == sorted({r["index"] for r in records})  # each trial once
    first = records[0]
    assert first["status"] == "done" and first["extra"]["robot_s"] >= kept["spent"]["robot_s"]
    assert first["extra"]["staging"]["rounds"] >= 0 and "placed" in first["extra"]["staging"]
