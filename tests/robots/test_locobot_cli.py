"""The host command line and the key tool: one-line errors, and keys that the host and client can load."""

from __future__ import annotations

import subprocess
import sys

import pytest
from lerobot_robot_locobot import host
from lerobot_robot_locobot.config_locobot import LocobotConfig
from lerobot_robot_locobot.keys import KeyFileError, create_keys, load_keys, main


def test_the_host_module_runs_and_refuses_to_listen_on_every_interface():
    result = subprocess.run(
        [sys.executable, "-m", "lerobot_robot_locobot.host", "--bind=0.0.0.0"], capture_output=True, text=True
    )
    assert result.returncode == 2 and result.stderr.startswith("error: --bind='0.0.0.0' would listen on every")


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--bind=0.0.0.0"], "every interface"),
        (["--bind=10.255.255.1"], "cannot listen on tcp://10.255.255.1:5555"),
        (["--speed=3"], "unknown flag '--speed=3'"),
        (["--watchdog_s=30"], "--watchdog_s"),
        (["--sim.collision=bounce"], "--sim.collision must be slide or stop"),
        (["--backend=ros2"], "ROS 2"),
        (["--authorized_keys=/tmp"], "--server_secret_key"),
        (["--server_secret_key=/nonexistent/server.key_secret"], "no key file at /nonexistent"),
    ],
)
def test_bad_host_flags_stop_with_one_line(args, message, capsys):
    assert host.main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and message in err and err.count("\n") == 1


def test_the_key_tool_writes_keys_for_both_sides_and_refuses_to_overwrite(tmp_path, capsys):
    assert main([str(tmp_path)]) == 0
    public, secret = load_keys(tmp_path / "client.key_secret", "--flag", secret=True)
    assert secret is not None and (tmp_path / "authorized_clients" / "client.key").read_bytes().count(public)
    assert main([str(tmp_path)]) == 2
    with pytest.raises(KeyFileError, match="only a public key"):
        load_keys(tmp_path / "server.key", "--robot.client_secret_key", secret=True)


def test_the_key_tool_runs_as_a_module_without_warnings(tmp_path):
    command = [sys.executable, "-W", "error", "-m", "lerobot_robot_locobot.keys", str(tmp_path)]
    result = subprocess.run(command, capture_output=True, text=True)
    assert result.returncode == 0 and result.stderr == "", result.stderr
    assert (tmp_path / "server.key_secret").is_file()


def test_client_key_options_go_together(tmp_path):
    create_keys(tmp_path)
    with pytest.raises(ValueError, match="set both or neither"):
        LocobotConfig(client_secret_key=tmp_path / "client.key_secret", calibration_dir=tmp_path)
