"""A serial arm lost mid-episode, as LeRobot's SO-101 follower loses it: an unplugged adapter raises pyserial's or
termios' errors, a failed disconnect leaves its port open, and the stop it is sent must hold its joints, not zero
them. The trial is aborted, the arm reconnects once it has power, and eval says one line, never a traceback."""

from __future__ import annotations

import errno
import os
import termios

import numpy as np
import pytest
import serial
from lerobot.utils.decorators import check_if_already_connected, check_if_not_connected

from lerobot_contrast import eval as eval_module
from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.record.observer import QuietObserver
from lerobot_contrast.spine import runner
from lerobot_contrast.spine.runner import RobotRunner, release
from tests.contrast.test_strategy import bases
from tests.contrast.toy_task import ToyTask

JOINTS = ("shoulder_pan.pos", "elbow_flex.pos")
UNPLUGGED = {
    "termios": lambda: termios.error(errno.EIO, "Input/output error"),
    "serial": lambda: serial.SerialException("device reports readiness to read but returned no data"),
    "link": lambda: ConnectionError("Failed to sync read 'Present_Position'"),
}


class Bus:
    """A motor bus as LeRobot's MotorsBus behaves: connected while its port is open; `disconnect` disables torque
    first, which fails once the servos have no power, leaving the port open; `connect` opens the port, then pings."""

    def __init__(self, arm: Arm) -> None:
        self.arm, self.is_open = arm, False

    @property
    def is_connected(self) -> bool:
        return self.is_open

    @check_if_already_connected
    def connect(self) -> None:
        self.is_open = True
        if not self.arm.powered:
            raise ConnectionError("Could not connect on port '/dev/ttyACM0'")

    @check_if_not_connected
    def disconnect(self, disable_torque: bool = True) -> None:
        if disable_torque and not self.arm.powered:
            raise ConnectionError("Failed to write 'Torque_Enable' on id_=1 after 6 tries")
        self.is_open = False


class Arm:
    """A position-controlled arm, LeRobot's way (`.pos` features, connect refused while connected), that can be
    unplugged after a number of actions and gets power back on a later connect."""

    name = "so101_follower"
    action_features = dict.fromkeys(JOINTS, float)
    observation_features = action_features

    def __init__(self, unplug_at: int | None = None, error: str = "termios", power_back_at: int = 2) -> None:
        self.bus, self.cameras = Bus(self), {}
        self.unplug_at, self.error, self.power_back_at = unplug_at, UNPLUGGED[error], power_back_at
        self.powered, self.connects, self.sent = True, 0, []
        self.joints = dict.fromkeys(JOINTS, 30.0)

    @property
    def is_connected(self) -> bool:
        return self.bus.is_connected

    @check_if_already_connected
    def connect(self, calibrate: bool = True) -> None:
        self.connects += 1
        self.powered = self.powered or self.connects >= self.power_back_at
        self.bus.connect()

    @check_if_not_connected
    def disconnect(self) -> None:
        self.bus.disconnect()

    def get_observation(self) -> dict[str, float]:
        if not self.powered:
            raise self.error()
        return dict(self.joints)

    def send_action(self, action: dict[str, float]) -> dict[str, float]:
        self.sent.append(dict(action))
        if self.unplug_at is not None and len(self.sent) == self.unplug_at:
            self.powered, self.connects = False, 0
        if not self.powered:
            raise self.error()
        self.joints = {key: self.joints[key] + 1.0 for key in JOINTS}
        return action

    def read_scene(self):
        return self.scene

    def stage_scene(self, scene) -> None:
        self.scene = scene


class Nudge:
    """A policy that moves every joint a degree a step."""

    def reset(self, context) -> None:
        pass

    def act(self, observation):
        return {key: observation[key] + 1.0 for key in JOINTS}


def trial(arm: Arm, observers=()) -> tuple[RobotRunner, object]:
    arm.connect()
    robot_runner = RobotRunner(arm, Nudge(), ToyTask(), operator=None, fps=None, max_steps=8, reconnect_s=1.0,
                               observers=observers)  # fmt: skip
    instance = bases(1)[0]
    context = TrialContext(0, instance, instance, instance.scene, 0.0, "reset", np.random.default_rng(0), 1)
    return robot_runner, robot_runner(context)


@pytest.fixture(autouse=True)
def quick_retries(monkeypatch):
    monkeypatch.setattr(runner, "RETRY_S", 0.01)


@pytest.mark.parametrize("error", UNPLUGGED)
def test_an_unplugged_arm_aborts_the_trial_and_reconnects_once_it_has_power(error):
    arm = Arm(unplug_at=3, error=error)
    robot_runner, outcome = trial(arm)
    assert outcome.status == "aborted" and outcome.extra["ended_by"] == "disconnected" and outcome.steps == 2
    # The failed disconnect and the first connect (unpowered) left the port open; the arm came back all the same.
    assert robot_runner.halted is None and arm.is_connected and arm.powered and arm.connects == 2


def test_an_arm_that_stays_unplugged_halts_the_session_with_one_clear_error():
    arm = Arm(unplug_at=3, power_back_at=10**9)  # never: with 10 ms retries, 1 s holds about 100 connects
    robot_runner, outcome = trial(arm)
    assert outcome.status == "aborted" and not arm.is_connected  # closed, so a later connect is not refused
    assert "could not reconnect within 1 s (Could not connect on port '/dev/ttyACM0')" in str(robot_runner.halted)
    assert arm.connects > 1


def test_the_stop_after_a_loss_holds_the_last_observed_positions_and_never_zeroes_them():
    arm = Arm(unplug_at=3)
    trial(arm)
    last_seen = {key: 32.0 for key in JOINTS}  # observed after the second action; the third was never confirmed
    assert arm.sent[3] == last_seen
    assert all(value != 0.0 for action in arm.sent for value in action.values())


def test_the_stop_zeroes_only_velocities_and_sends_nothing_where_no_position_was_observed():
    arm = Arm()
    arm.action_features = {"shoulder_pan.pos": float, "base.vel": float}
    robot_runner, _ = trial(arm)
    arm.sent.clear()
    robot_runner._hold({"shoulder_pan.pos": 12.5, "base.vel": 0.3})
    robot_runner._hold(None)
    robot_runner._hold({"base.vel": 0.3})
    assert arm.sent == [{"shoulder_pan.pos": 12.5, "base.vel": 0.0}]


def test_an_oserror_of_our_own_files_is_not_taken_for_a_lost_robot():
    class FullDisk(QuietObserver):
        def step(self, timestamp_s, observation, action):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    arm = Arm()
    with pytest.raises(OSError, match="No space left"):
        trial(arm, observers=[FullDisk()])
    assert arm.connects == 1  # no reconnect was tried


def test_releasing_a_lost_arm_closes_its_port_and_returns_why_it_did_not_disconnect_cleanly():
    arm = Arm()
    arm.connect()
    arm.powered = False
    assert "Torque_Enable" in str(release(arm)) and not arm.is_connected
    arm.connect()
    assert release(arm) is None and not arm.is_connected


def test_eval_ends_with_the_error_line_and_one_short_line_when_the_lost_arm_cannot_disconnect(monkeypatch, capsys):
    arm = Arm()

    def lost(cfg, evaluation):
        arm.powered = False
        print("error: the robot (so101_follower) disconnected and could not reconnect", file=eval_module.sys.stderr)
        return 2

    monkeypatch.setattr(eval_module, "make_robot", lambda cfg, chosen: arm)
    monkeypatch.setattr(eval_module, "make_operator", lambda *args: None)
    monkeypatch.setattr(eval_module, "make_policy", lambda *args: None)
    monkeypatch.setattr(eval_module, "equipped", lambda *args: None)
    monkeypatch.setattr(eval_module, "run_and_report", lost)
    code = eval_module.main(["--task=language_table", "--n_instances=1", "--policy.type=oracle", "--rerun=false"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and not arm.is_connected
    assert err[0].startswith("error: ") and len(err) == 2 and "did not disconnect cleanly" in err[1], err
