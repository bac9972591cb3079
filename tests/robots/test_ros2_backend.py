"""The ros2 backend's closed-loop motions against a fake of the ROS interface (no ROS needed)."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from lerobot_robot_locobot.backend_ros2 import Ros2Backend, SceneIONotSupported
from lerobot_robot_locobot.config_host import Ros2Config
from lerobot_robot_locobot.odometry import wrap


class FakeDriver:
    """A differential base that covers only `slip` of the commanded speed (worn wheels, a soft carpet), with a
    640x480 camera. It moves between calls according to `clock`."""

    def __init__(self, clock=time.monotonic, slip: float = 0.8, start=(0.0, 0.0, 0.0)) -> None:
        self.clock, self.slip, self.pose = clock, slip, start
        self.command = (0.0, 0.0)
        self.commands: list[tuple[float, float]] = []
        self.bumped = False
        self._last = clock()

    def _advance(self) -> None:
        now = self.clock()
        dt, self._last = now - self._last, now
        x, theta = self.command
        yaw = self.pose[2] + theta * self.slip * dt
        step = x * self.slip * dt
        self.pose = (self.pose[0] + step * math.cos(yaw), self.pose[1] + step * math.sin(yaw), wrap(yaw))

    def command_velocity(self, x: float, theta: float) -> None:
        self._advance()
        self.command = (x, theta)
        self.commands.append(self.command)

    def odometry(self):
        self._advance()
        return self.pose

    def bumper(self) -> bool:
        return self.bumped

    def color(self):
        return 7, np.full((480, 640, 3), 90, np.uint8)

    def depth(self):
        return np.full((480, 640), 2.5, np.float32)

    def shutdown(self) -> None:
        self.command = (0.0, 0.0)


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def backend_with(clock: Clock, **driver_args) -> tuple[Ros2Backend, FakeDriver]:
    driver = FakeDriver(clock, **driver_args)
    return Ros2Backend(Ros2Config(step_timeout_s=3.0), driver=driver, clock=clock), driver


def run(backend: Ros2Backend, clock: Clock, limit_s: float = 20.0, dt: float = 0.01) -> str:
    while clock.now < limit_s:
        result = backend.update(dt)
        if result is not None:
            return result
        clock.now += dt
    raise AssertionError("the motion never finished")


def test_a_forward_step_reaches_its_distance_on_odometry_despite_wheel_slip():
    clock = Clock()
    backend, driver = backend_with(clock, slip=0.8)
    backend.start_step("forward", 0.25)
    assert backend.moving
    assert run(backend, clock) == "done"
    assert driver.pose[0] == pytest.approx(0.25, abs=0.011) and driver.pose[1] == pytest.approx(0.0)
    assert driver.commands[-1] == (0.0, 0.0) and not backend.moving
    assert max(x for x, _ in driver.commands) <= 0.2  # the configured cruising speed


@pytest.mark.parametrize(("command", "start", "end"), [("turn_left", 170, -160), ("turn_right", -170, 160)])
def test_turns_reach_their_angle_across_the_wrap_around(command, start, end):
    clock = Clock()
    backend, driver = backend_with(clock, start=(1.0, 2.0, math.radians(start)))
    backend.start_step(command, math.radians(30))
    assert run(backend, clock) == "done"
    assert math.degrees(driver.pose[2]) == pytest.approx(end, abs=1.6)
    assert driver.pose[:2] == pytest.approx((1.0, 2.0))


def test_the_bumper_ends_a_forward_step_and_stops_the_base():
    clock = Clock()
    backend, driver = backend_with(clock)
    backend.start_step("forward", 0.25)
    for _ in range(30):
        assert backend.update(0.01) is None
        clock.now += 0.01
    driver.bumped = True
    assert backend.update(0.01) == "blocked"
    assert driver.command == (0.0, 0.0) and 0.0 < driver.pose[0] < 0.25


def test_a_base_that_does_not_move_times_out():
    clock = Clock()
    backend, driver = backend_with(clock, slip=0.0)
    backend.start_step("turn_left", math.radians(30))
    assert run(backend, clock) == "timeout"
    assert driver.command == (0.0, 0.0) and clock.now == pytest.approx(3.0, abs=0.05)


def test_stop_abandons_a_running_step_and_a_stop_step_finishes_at_once():
    clock = Clock()
    backend, driver = backend_with(clock)
    backend.start_step("forward", 0.25)
    backend.update(0.01)
    assert backend.stop() and driver.command == (0.0, 0.0) and not backend.moving
    backend.start_step("stop", 0.0)
    assert backend.update(0.01) == "done"


def test_velocity_commands_are_republished_while_moving_and_images_fit_the_client_size():
    clock = Clock()
    backend, driver = backend_with(clock)
    backend.set_velocity(0.1, 0.2)
    backend.update(0.01)
    backend.update(0.01)
    assert driver.commands == [(0.1, 0.2), (0.1, 0.2)]
    backend.configure_camera(160, 120, depth=True)
    key, rgb, depth = backend.images()
    assert rgb.shape == (120, 160, 3) and depth.shape == (120, 160) and depth[0, 0] == pytest.approx(2.5)
    with pytest.raises(SceneIONotSupported):
        backend.read_scene()
