"""The real host (simulated apartment) and client over loopback: observations, exactly-once steps under loss
and reordering, the watchdog, reconnection, refused clients, scene I/O."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from lerobot_robot_locobot import Locobot, LocobotConnectionError, SceneIOUnavailable, one_hot
from lerobot_robot_locobot.backend_ros2 import Ros2Backend
from lerobot_robot_locobot.config_host import HostConfig, Ros2Config, SimConfig
from lerobot_robot_locobot.host import HostThread
from lerobot_robot_locobot.keys import create_keys

from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.domains.vln.locobot_sim import SimBackend
from lerobot_contrast.ports import free_port
from tests.robots.locobot_helpers import (
    FREE_PORTS,
    ChaosProxy,
    CountingBackend,
    DyingBackend,
    client_config,
)
from tests.robots.test_ros2_backend import FakeDriver


@pytest.fixture
def connect(tmp_path):
    robots = []

    def make(ports, **changes):
        robot = Locobot(client_config(ports, tmp_path, **changes))
        robot.connect()
        robots.append(robot)
        return robot

    yield make
    for robot in robots:
        if robot.is_connected:
            robot.disconnect()


def heading(robot: Locobot) -> float:
    return robot.get_observation()["odom.theta"]


def test_an_observation_carries_the_state_and_the_rendered_camera_image(connect):
    backend = SimBackend(SimConfig())
    with HostThread(FREE_PORTS, backend) as host:
        robot = connect(host.ports, use_depth=True)
        observation = robot.get_observation()
        assert set(observation) == set(robot.observation_features)
        assert (observation["odom.x"], observation["odom.y"]) == pytest.approx((4.0, 2.6))
        assert observation["front"].shape == (120, 160, 3) and observation["front"].dtype == np.uint8
        _, rgb, depth = backend.images()
        assert np.abs(observation["front"].astype(int) - rgb).mean() < 4  # JPEG
        assert np.abs(observation["front_depth"][..., 0] - depth).max() <= 0.0006  # millimetre PNG


def test_discrete_steps_move_and_turn_by_the_configured_amounts(connect):
    with HostThread(FREE_PORTS) as host:
        robot = connect(host.ports, turn_deg=15.0)
        start = robot.get_observation()
        assert robot.send_action(one_hot("turn_left")) == one_hot("turn_left")
        assert heading(robot) == pytest.approx(math.radians(15))
        robot.send_action(one_hot("turn_right"))
        robot.send_action(one_hot("forward"))
        moved = robot.get_observation()
        assert (moved["odom.x"] - start["odom.x"], moved["odom.y"] - start["odom.y"]) == pytest.approx((0.25, 0.0))
        assert robot.send_action(one_hot(None)) == one_hot(None)  # all zeros: nothing happens
        robot.send_action(one_hot("stop"))
        assert robot.stop_requested


@pytest.mark.parametrize("seed", [0, 1])
def test_each_discrete_step_runs_exactly_once_when_messages_are_lost_repeated_and_reordered(connect, seed):
    backend = CountingBackend(SimBackend(SimConfig()))
    with HostThread(FREE_PORTS, backend) as host:
        proxy = ChaosProxy(host.ports, seed)
        try:
            robot = connect(proxy.ports)
            for _ in range(7):
                robot.send_action(one_hot("turn_left"))
            assert [command for command, _ in backend.started] == ["turn_left"] * 7
            assert heading(robot) == pytest.approx(math.remainder(math.radians(7 * 30), 2 * math.pi))
            assert proxy.stats["dropped"] and proxy.stats["repeated"] and proxy.stats["held"]
        finally:
            proxy.close()


def test_the_watchdog_stops_the_base_when_commands_stop(connect):
    with HostThread(FREE_PORTS) as host:
        robot = connect(host.ports, action_mode="velocity")
        before = robot.get_observation()
        sent = time.monotonic()
        assert robot.send_action({"x.vel": 0.2, "theta.vel": 0.0}) == {"x.vel": 0.2, "theta.vel": 0.0}
        while robot.get_observation()["x.vel"] != 0.2:
            assert time.monotonic() - sent < 0.5, "the base never started"
        while robot.get_observation()["x.vel"] != 0.0:
            assert time.monotonic() - sent < 1.5, "the base kept moving without commands"
        stopped = time.monotonic() - sent
        resting = robot.get_observation()["odom.x"]
        time.sleep(0.2)
        assert robot.get_observation()["odom.x"] == resting
        assert 0.2 * 0.4 < resting - before["odom.x"] < 0.2 * stopped + 0.02
        assert host.config.watchdog_s == 0.5


def test_velocities_are_clamped_by_client_and_host(connect):
    config = HostConfig(port_command=0, port_observation=0, port_rpc=0, max_x_vel=0.1)
    with HostThread(config) as host:
        robot = connect(host.ports, action_mode="velocity")
        assert robot.send_action({"x.vel": 5.0, "theta.vel": -9.0}) == {"x.vel": 0.3, "theta.vel": -1.0}
        deadline = time.monotonic() + 2.0
        while robot.get_observation()["x.vel"] != pytest.approx(0.1):
            assert time.monotonic() < deadline
        with pytest.raises(ValueError, match="theta.vel"):
            robot.send_action({"x.vel": 0.1})


def test_a_client_reconnects_and_survives_a_host_restart_between_steps(connect):
    ports = {"command": free_port(), "observation": free_port(), "rpc": free_port()}
    config = HostConfig(port_command=ports["command"], port_observation=ports["observation"], port_rpc=ports["rpc"])
    with HostThread(config):
        robot = connect(ports)
        robot.send_action(one_hot("turn_left"))
        robot.disconnect()
        robot.connect()  # a new session on the same host
        robot.send_action(one_hot("turn_left"))
        assert heading(robot) == pytest.approx(math.radians(60))
    with HostThread(config):  # the host process restarts; the client notices at its next observation
        time.sleep(0.3)
        assert heading(robot) == pytest.approx(0.0)
        robot.send_action(one_hot("turn_right"))
        assert heading(robot) == pytest.approx(math.radians(-30))


@pytest.mark.parametrize("publish_hz", [30.0, 60.0])
def test_a_host_that_dies_mid_step_is_given_up_after_its_publishing_periods_not_the_step_timeout(connect, publish_hz):
    backend = DyingBackend(SimBackend(SimConfig()), dies_at=2)
    thread = HostThread(HostConfig(port_command=0, port_observation=0, port_rpc=0, publish_hz=publish_hz), backend)
    backend.host_stop = thread.stop_event
    with thread as host:
        robot = connect(host.ports)
        assert robot._link.lost_after_s == pytest.approx(60 / publish_hz)  # LOST_PERIODS of the host's period
        robot.send_action(one_hot("turn_left"))
        start = time.monotonic()
        with pytest.raises(
            LocobotConnectionError,
            match=rf"fell silent during step 2 \(turn_left\): no observation for {60 / publish_hz:g} s",
        ):
            robot.send_action(one_hot("turn_left"))
        assert time.monotonic() - start < 60 / publish_hz + 1.0 < robot.config.step_timeout_s


def test_the_silence_limit_can_be_set(connect):
    with HostThread(FREE_PORTS) as host:
        assert connect(host.ports, observation_timeout_s=0.7)._link.lost_after_s == 0.7


def test_a_client_that_cannot_reach_the_host_fails_with_one_line_naming_the_address(tmp_path):
    port = free_port()
    robot = Locobot(client_config({"command": free_port(), "observation": free_port(), "rpc": port}, tmp_path))
    robot.config.connect_timeout_s = 0.3
    with pytest.raises(LocobotConnectionError) as error:
        robot.connect()
    assert f"tcp://127.0.0.1:{port}" in str(error.value) and "\n" not in str(error.value)
    assert not robot.is_connected


def test_with_curve_keys_only_authorised_clients_get_in(connect, tmp_path):
    create_keys(tmp_path / "keys")
    stranger = tmp_path / "stranger"
    create_keys(stranger)
    keys = tmp_path / "keys"
    config = HostConfig(
        port_command=0, port_observation=0, port_rpc=0,
        server_secret_key=keys / "server.key_secret", authorized_keys=keys / "authorized_clients",
    )  # fmt: skip
    with HostThread(config) as host:
        robot = connect(host.ports, client_secret_key=keys / "client.key_secret", server_public_key=keys / "server.key")
        robot.send_action(one_hot("turn_left"))
        assert heading(robot) == pytest.approx(math.radians(30))
        for secret in (None, stranger / "client.key_secret"):
            server = None if secret is None else keys / "server.key"
            with pytest.raises(LocobotConnectionError, match="no answer"):
                connect(host.ports, connect_timeout_s=0.5, client_secret_key=secret, server_public_key=server)
        assert heading(robot) == pytest.approx(math.radians(30))  # the refused clients moved nothing


def test_scenes_are_staged_and_read_back_in_simulation(connect):
    with HostThread(FREE_PORTS) as host:
        robot = connect(host.ports)
        assert robot.supports_scene_io
        scene = Scene({"couch": Pose(2.0, 2.0, 0.5), "lamp": Pose(6.0, 4.0)}, robot=Pose(5.0, 1.0, math.pi / 2))
        robot.stage_scene(scene)
        assert Scene.from_json(robot.read_scene()) == scene
        observation = robot.get_observation()  # odometry reads in the scene frame from the staged pose
        assert (observation["odom.x"], observation["odom.y"], observation["odom.theta"]) == pytest.approx(
            (5.0, 1.0, math.pi / 2)
        )
        robot.send_action(one_hot("forward"))
        assert Scene.from_json(robot.read_scene()).robot.y == pytest.approx(1.25)
        with pytest.raises(Exception, match="collides with couch"):
            robot.stage_scene(scene.with_robot(Pose(2.0, 2.0)))


def test_odometry_can_be_anchored_to_a_pose(connect):
    with HostThread(FREE_PORTS) as host:
        robot = connect(host.ports)
        robot.set_odometry(1.0, 2.0, 0.0)
        robot.send_action(one_hot("forward"))
        observation = robot.get_observation()
        assert (observation["odom.x"], observation["odom.y"]) == pytest.approx((1.25, 2.0))


def test_a_real_robot_host_reports_no_scene_io(connect):
    backend = Ros2Backend(Ros2Config(), driver=FakeDriver())
    with HostThread(FREE_PORTS, backend) as host:
        robot = connect(host.ports)
        assert not robot.supports_scene_io and "set_odometry" in robot.capabilities
        with pytest.raises(SceneIOUnavailable, match="operator"):
            robot.read_scene()
