"""The twin as a user runs it: one command starts it and prints the flags for eval, LeRobot's own SO101Follower
connects with them, objects are placed by command (bad requests get one line), and SIGTERM stops it cleanly."""

import json
import math
import re
import signal
import socket
import subprocess
import sys
import time

import pytest
import zmq

from lerobot_contrast.domains.task_file import load_task_file
from lerobot_contrast.ports import free_port
from lerobot_contrast.so101 import arm
from lerobot_contrast.so101.scene import build_spec
from lerobot_contrast.twin.physics import Physics
from lerobot_contrast.twin.placement import PlacementServer
from lerobot_contrast.twin.placement_client import request
from lerobot_contrast.twin.servos import ServoBank
from tests.twin.test_bus import connected

POSE = {"shoulder_pan.pos": 20.0, "shoulder_lift.pos": -30.0, "elbow_flex.pos": 40.0, "wrist_flex.pos": 60.0,
        "wrist_roll.pos": 15.0, "gripper.pos": 40.0}  # fmt: skip
STARTUP_S = 90  # a loaded 2-core CI machine imports LeRobot and compiles the model in well under this


@pytest.fixture(scope="module")
def placement():
    task = load_task_file("so101_blocks").spec
    physics = Physics(build_spec(task), ServoBank(arm.MOTORS, arm.rest_raw(), limits=arm.raw_limits()), task.objects)
    return PlacementServer(physics, task, port=free_port())


def answer(server: PlacementServer, message) -> dict:
    return server.answer(message if isinstance(message, bytes) else json.dumps(message).encode())


@pytest.mark.parametrize(
    ("message", "error"),
    [
        (b"put it there", r"^malformed request: send one JSON object"),
        ([1, 2], r"^malformed request"),
        ({"cmd": "teleport"}, r"^unknown command 'teleport' in \"cmd\"; use one of: place, scene, board"),
        ({"cmd": "place", "object": "purple_cube", "x": 0.3, "y": 0.0}, r"^unknown object 'purple_cube'; .* red_cube"),
        ({"cmd": "place", "object": "red_cube", "x": 30, "y": 10}, r"^\(30.000, 10.000\) m is off the table.*metres"),
        ({"cmd": "place", "object": "red_cube", "x": "0.3", "y": 0.0}, r"^place: 'x' must be a finite number"),
        ({"cmd": "place", "object": "red_cube", "x": 0.3, "y": math.inf}, r"^place: 'y' must be a finite number"),
        ({"cmd": "board", "x": 0.3, "y": 0.0}, r"^board: 'yaw_deg' must be a finite number, got None"),
    ],
)
def test_bad_requests_get_one_line(placement, message, error):
    reply = answer(placement, message)
    assert reply["ok"] is False and "\n" not in reply["error"]
    assert re.search(error, reply["error"])


def test_place_then_scene_reports_the_true_pose(placement):
    reply = answer(placement, {"cmd": "place", "object": "red_cube", "x": 0.31, "y": -0.05, "yaw": 0.4})
    assert reply == {"ok": True, "moved_aside": []}
    placement.physics.run(0.3)
    scene = answer(placement, {"cmd": "scene"})
    assert scene["objects"]["red_cube"] == pytest.approx([0.31, -0.05, 0.4], abs=0.001)
    assert scene["z"]["red_cube"] == pytest.approx(0.015, abs=0.001)


def test_placing_onto_another_object_puts_that_one_back_where_it_waits(placement):
    physics = placement.physics
    answer(placement, {"cmd": "place", "object": "blue_cube", "x": 0.25, "y": 0.05})
    reply = answer(placement, {"cmd": "place", "object": "green_cube", "x": 0.26, "y": 0.05})
    assert reply == {"ok": True, "moved_aside": ["blue_cube"]}
    physics.run(0.3)
    poses = physics.poses()
    assert poses["green_cube"][:2] == pytest.approx((0.26, 0.05), abs=0.001)
    assert poses["blue_cube"][:2] == pytest.approx((placement.parked["blue_cube"].x, placement.parked["blue_cube"].y))


def test_a_fixed_object_cannot_be_placed():
    from lerobot_contrast.domains.task_file import task_from_dict
    from tests.twin.test_scene import other_task

    task = task_from_dict(other_task()).spec
    physics = Physics(build_spec(task), ServoBank(arm.MOTORS, arm.rest_raw(), limits=arm.raw_limits()), task.objects)
    reply = answer(
        PlacementServer(physics, task, port=free_port()), {"cmd": "place", "object": "stand", "x": 0.2, "y": 0}
    )
    assert reply == {"ok": False, "error": "stand is fixed in the task file (movable: false); it cannot be placed"}


def test_the_board_is_laid_and_removed_without_moving_anything(placement):
    physics = placement.physics
    before = physics.poses()
    assert answer(placement, {"cmd": "board", "x": 0.3, "y": 0.0, "yaw_deg": 10}) == {"ok": True}
    assert physics.model.geom("calibration_board").size[2] > 0 and physics.version == 1
    for name, pose in physics.poses().items():
        assert pose == pytest.approx(before[name])
    assert answer(placement, {"cmd": "remove_board"}) == {"ok": True, "removed": True}
    assert answer(placement, {"cmd": "remove_board"}) == {"ok": True, "removed": False}


def test_a_command_that_fails_inside_the_twin_is_an_error_reply_not_a_dead_socket(placement, monkeypatch):
    def broken(change):
        raise RuntimeError("XML Error: something\nwith two lines")

    monkeypatch.setattr(placement.physics, "edit", broken)
    reply = answer(placement, {"cmd": "board", "x": 0.3, "y": 0.0, "yaw_deg": 0})
    assert reply == {"ok": False, "error": "board failed in the twin: XML Error: something with two lines"}


def test_reset_arm_puts_it_at_rest(placement):
    physics = placement.physics
    physics.bank.memory(arm.MOTORS["shoulder_pan"][0]).write("Torque_Enable", 1)
    physics.bank.memory(arm.MOTORS["shoulder_pan"][0]).write("Goal_Position", 2600)
    physics.run(1.0)
    assert answer(placement, {"cmd": "reset_arm"}) == {"ok": True}
    physics.run(0.5)
    for name in arm.MOTOR_NAMES:
        assert arm.to_angle(name, physics.bank.present(name)) == pytest.approx(arm.REST[name], abs=math.radians(1))


def twin_command(*flags: str) -> list[str]:
    return [sys.executable, "-m", "lerobot_contrast.twin", *flags]


def run_twin(*flags: str) -> subprocess.CompletedProcess:
    return subprocess.run(twin_command(*flags), capture_output=True, text=True, timeout=STARTUP_S)


@pytest.mark.parametrize(
    ("flags", "error"),
    [
        (["--task=no_such_task"], "error: --task: 'no_such_task' is neither a task file path nor one of:"),
        (["--camera_prot=5555"], "error: unknown flag --camera_prot; did you mean --camera_port?"),
        (["--lens_k1=wide"], "error: --lens_k1:"),
        (["--camera_port=70000"], "error: --camera_port=70000 is not a port: give one from 1 to 65535"),
        (["--control_port=0"], "error: --control_port=0 is not a port: give one from 1 to 65535"),
        (["--camera_port=6001", "--control_port=6001"], "error: --camera_port and --control_port are both 6001"),
        (["--width=0"], "error: --width=0: give a whole number above 0"),
    ],
)
def test_bad_flags_are_one_line(flags, error):
    done = run_twin(*flags)
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.startswith(error) and done.stderr.count("\n") == 1


def test_a_port_in_use_is_one_line_before_the_model_loads(tmp_path):
    context = zmq.Context()
    taken = context.socket(zmq.REP)
    port = taken.bind_to_random_port("tcp://127.0.0.1")
    try:
        done = run_twin(f"--control_port={port}", f"--camera_port={free_port()}", f"--calibration_dir={tmp_path}")
    finally:
        taken.close()
        context.term()
    assert done.returncode == 2 and done.stdout == ""
    assert (
        done.stderr
        == f"error: control port {port} on 127.0.0.1: Address already in use; choose a free one with --control_port\n"
    )
    assert not (tmp_path / "twin.json").exists()


@pytest.mark.realtime
@pytest.mark.slow
def test_one_command_starts_a_bench_lerobot_connects_to_and_sigterm_stops(tmp_path):
    from lerobot.robots.so_follower import SO101Follower, SO101FollowerConfig

    camera_port, control_port = free_port(), free_port()
    flags = [f"--calibration_dir={tmp_path}", f"--camera_port={camera_port}", f"--control_port={control_port}",
             "--width=160", "--height=120", "--fps=5"]  # fmt: skip
    twin = subprocess.Popen(twin_command(*flags), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        lines = [twin.stdout.readline() for _ in range(6)]
        assert [line.split(":")[0] for line in lines] == ["bus", "camera", "placement", "calibration", "clock",
                                                          "eval flags"]  # fmt: skip
        assert lines[4] == "clock: wall (real time)\n"
        port = lines[0].split()[1]
        assert f"--robot.port={port} --robot.id=twin --robot.calibration_dir={tmp_path}" in lines[5]
        assert f"port: {camera_port}" in lines[5] and "type: zmq" in lines[5] and "--clock" not in lines[5]
        assert (tmp_path / "twin.json").is_file()

        config = SO101FollowerConfig(port=port, id="twin", calibration_dir=tmp_path)
        robot = connected(lambda: SO101Follower(config))  # retried: LeRobot's 50 ms reply deadline on a loaded machine
        try:
            assert robot.is_calibrated
            observed = robot.get_observation()
            for name in arm.MOTOR_NAMES:
                assert observed[f"{name}.pos"] == pytest.approx(arm.to_lerobot(name, arm.REST[name]), abs=2.0)
            robot.send_action(POSE)
            time.sleep(1.5)  # the twin runs in real time: servos at finite speed, the physics behind them
            reached = robot.get_observation()
        finally:
            robot.disconnect()
        for key, value in POSE.items():
            assert reached[key] == pytest.approx(value, abs=2.0)

        place = [sys.executable, "-m", "lerobot_contrast.twin.place", f"--control_port={control_port}"]
        placed = subprocess.run([*place, "green_cube", "0.25", "0.0", "30"], capture_output=True, text=True, timeout=60)
        assert placed.stdout == "placed green_cube at x=0.250 y=0.000 m, yaw 30 deg\n"
        wrong = subprocess.run([*place, "green_cube", "30", "10"], capture_output=True, text=True, timeout=60)
        assert wrong.returncode == 1 and wrong.stderr.startswith("error: (30.000, 10.000) m is off the table")
        assert request({"cmd": "scene"}, control_port)["objects"]["green_cube"] == pytest.approx(
            [0.25, 0.0, 0.5236], abs=0.002
        )
    finally:
        twin.send_signal(signal.SIGTERM)
        _, stderr = twin.communicate(timeout=30)
    assert twin.returncode == 0, stderr
    assert stderr.strip().endswith("twin stopped")
    with socket.socket() as s:
        s.bind(("127.0.0.1", control_port))  # its sockets went with it


def test_the_place_command_takes_metres_and_degrees_and_names_bad_input():
    from lerobot_contrast.contrast.errors import UserError
    from lerobot_contrast.twin.place import parse

    command, port = parse(["red_cube", "0.3", "-0.1", "90", "--control_port", "5999"])
    assert port == 5999 and command == {"cmd": "place", "object": "red_cube", "x": 0.3, "y": -0.1, "yaw": math.pi / 2}
    assert parse(["scene"]) == ({"cmd": "scene"}, 5556)
    for argv, error in [
        (["red_cube", "0.3"], "usage: python -m lerobot_contrast.twin.place OBJECT X Y [YAW]"),
        (["red_cube", "left", "0"], "X='left' is not a number"),
        (["red_cube", "0", "0", "--port=3"], "unknown flag --port"),
    ]:
        with pytest.raises(UserError, match=re.escape(error)):
            parse(argv)


def test_no_twin_answering_is_one_line():
    from lerobot_contrast.contrast.errors import UserError

    port = free_port()
    with pytest.raises(UserError, match=rf"^no twin answers on tcp://127.0.0.1:{port} within 0.2 s; start it with"):
        request({"cmd": "scene"}, port, timeout_s=0.2)


def test_a_twin_stops_when_the_process_that_started_it_is_killed():
    """A benchmark or test killed with SIGKILL runs no clean-up: its twin must not live on, holding ports and a core."""
    starter = (
        "from lerobot_contrast.twin.launch import running_twin\n"
        "print(running_twin().__enter__().process.pid, flush=True)\ninput()"
    )
    parent = subprocess.Popen([sys.executable, "-c", starter], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    twin = int(parent.stdout.readline())
    parent.kill()
    parent.wait()
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and _alive(twin):
        time.sleep(0.2)
    assert not _alive(twin)


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().split(")")[-1].split()[0] != "Z"  # a zombie has exited
    except FileNotFoundError:
        return False
