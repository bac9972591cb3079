"""The twin on its own clock (--clock=sim): LeRobot's so101_follower and zmq camera, unmodified, see a world that
moves only when the evaluator's clock advances it, and the same advances give the same readings and frames however
busy the machine is."""

from __future__ import annotations

import multiprocessing
import re
import shlex
import time

import pytest

from lerobot_contrast.clock.robot_clock import WallClock, robot_clock, use_clock
from lerobot_contrast.clock.simulated import pixels_crc
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.ports import free_port
from lerobot_contrast.twin.clock_server import ClockServer
from lerobot_contrast.twin.launch import running_twin
from lerobot_contrast.twin.placement_client import PlacementClient
from lerobot_contrast.twin.process import TwinConfig

POSE = {"shoulder_pan.pos": 20.0, "shoulder_lift.pos": -30.0, "elbow_flex.pos": 40.0, "wrist_flex.pos": 60.0,
        "wrist_roll.pos": 0.0, "gripper.pos": 30.0}  # fmt: skip
SMALL = ("--clock=sim", "--width=160", "--height=120")


def connected_robot(twin):
    from lerobot_contrast.spine.build import make_robot, register_robots
    from lerobot_contrast.spine.config import EvalConfig
    from lerobot_contrast.spine.flags import parse_config
    from lerobot_contrast.spine.run_setup import connect

    register_robots()
    cfg = parse_config(EvalConfig, ["--task=so101_blocks", *shlex.split(twin.robot_flags)])
    assert cfg.clock.startswith("tcp://")  # the twin's eval flags carry its clock
    robot = make_robot(cfg)
    connect(robot, cfg.clock)
    return robot


def hog() -> None:
    while True:
        pass


def rehearse(steps: int = 45) -> list[tuple]:
    """Drive a fresh twin toward POSE at 30 Hz on its clock; every step's joint readings and frame."""
    with running_twin(*SMALL) as twin:
        robot = connected_robot(twin)
        try:
            start = robot.get_observation()
            seen = []
            for step in range(1, steps + 1):
                share = min(1.0, step / 30)
                robot.send_action({k: start[k] + share * (v - start[k]) for k, v in POSE.items()})
                robot_clock().sleep(1 / 30)
                observed = robot.get_observation()
                seen.append((tuple(observed[k] for k in POSE), pixels_crc(observed["front"])))
            assert robot_clock().late_frames == 0
            return seen
        finally:
            robot.disconnect()


@pytest.mark.slow
def test_the_world_moves_only_when_the_clock_advances_it():
    with running_twin(*SMALL) as twin:
        robot = connected_robot(twin)
        try:
            clock = robot_clock()
            assert clock.simulated and clock.now() == 0.0
            before = robot.get_observation()
            robot.send_action(POSE)
            time.sleep(1.0)  # real time passes; the twin's does not
            paused = robot.get_observation()
            assert paused["shoulder_pan.pos"] == pytest.approx(before["shoulder_pan.pos"], abs=0.5)
            assert pixels_crc(paused["front"]) == pixels_crc(before["front"])
            clock.sleep(1.5)
            reached = robot.get_observation()
            assert clock.now() == pytest.approx(1.5)
            assert PlacementClient(twin.placement).time() == pytest.approx(1.5)
            for key, value in POSE.items():
                assert reached[key] == pytest.approx(value, abs=2.0)
            assert pixels_crc(reached["front"]) != pixels_crc(before["front"])  # the camera saw the arm move
        finally:
            robot.disconnect()


@pytest.mark.slow
def test_the_same_advances_give_the_same_readings_and_frames_beside_a_cpu_hog():
    idle = rehearse()
    hogs = [multiprocessing.get_context("spawn").Process(target=hog, daemon=True) for _ in range(2)]
    for process in hogs:
        process.start()
    try:
        loaded = rehearse()
    finally:
        for process in hogs:
            process.terminate()
    assert loaded == idle
    assert idle[-1][0] == pytest.approx(tuple(POSE.values()), abs=2.0)


def test_a_clock_nobody_serves_is_one_line():
    with pytest.raises(UserError, match="no twin's clock answers there; start one with"):
        use_clock(f"tcp://127.0.0.1:{free_port()}")
    with pytest.raises(UserError, match="--clock=soon: give wall, or the tcp://HOST:PORT"):
        use_clock("soon")
    assert isinstance(use_clock("wall"), WallClock)


@pytest.mark.parametrize(
    ("config", "error"),
    [
        (TwinConfig(clock="fast"), "--clock=fast: give wall (real time) or sim"),
        (TwinConfig(clock="sim", clock_port=5555), "--camera_port and --clock_port are both 5555: give two ports"),
    ],
)
def test_bad_clock_flags_are_one_line(config, error):
    with pytest.raises(UserError, match=re.escape(error)):
        config.check()


class Counted:
    """What the clock server drives, counting what it is asked: physics ticks, bus drains, camera captures."""

    def __init__(self):
        self.ticks, self.drains, self.captures = 0, 0, []

    def tick(self):
        self.ticks += 1

    def drain(self):
        self.drains += 1

    def capture(self, instant):
        self.captures.append(instant)
        return len(self.captures)


def test_the_clock_steps_the_time_asked_and_draws_a_frame_at_each_frame_instant():
    world = Counted()
    server = ClockServer(world, world, world, fps=30, port=free_port())
    try:
        replies = [server.answer(b'{"cmd": "advance", "seconds": 0.03333333333333333}') for _ in range(30)]
        assert world.ticks == 100 and world.drains == 30  # 1 s at 100 Hz, the bus drained before each step
        assert [r["frame"] for r in replies] == list(range(1, 31)) and replies[-1]["time"] == pytest.approx(1.0)
        moving = server.answer(b'{"cmd": "advance", "seconds": 0.5, "frame": false}')  # the arm moving itself
        assert moving == {"ok": True, "time": pytest.approx(1.5), "frame": None} and len(world.captures) == 30
        assert server.answer(b'{"cmd": "advance", "seconds": 0.004}')["frame"] == 31  # the frame instant passed
        assert server.answer(b'{"cmd": "time"}') == {"ok": True, "time": pytest.approx(1.504)}
        assert world.ticks == 150
        refused = server.answer(b'{"cmd": "advance", "seconds": -1}')
        assert refused == {"ok": False, "error": "advance: 'seconds' must be from 0 to 600, got -1"}
        assert server.answer(b'{"cmd": "rewind"}')["error"].startswith("unknown command 'rewind'")
    finally:
        server.stop()
