"""End to end over loopback: the host with the simulated apartment, the LoCoBot client, the scripted navigator,
driven by the same RobotRunner and eval CLI as on hardware."""

from __future__ import annotations

import json
import time

import pytest
from lerobot_robot_locobot import Locobot
from lerobot_robot_locobot.host import HostThread

from lerobot_contrast.contrast.staging import SceneIO
from lerobot_contrast.domains.vln import VLNTask
from lerobot_contrast.eval import main
from lerobot_contrast.policies.route_follower import RouteFollower
from lerobot_contrast.spine.runner import RobotRunner
from tests.policies.test_route_follower import context_for
from tests.robots.locobot_helpers import FREE_PORTS, client_config

TASK = VLNTask()


@pytest.fixture
def host():
    with HostThread(FREE_PORTS) as host:
        yield host


def test_a_vln_episode_over_loopback_reaches_both_subgoals(host, tmp_path):
    robot = Locobot(client_config(host.ports, tmp_path))
    robot.connect()
    assert isinstance(robot, SceneIO) and robot.supports_scene_io
    instance = TASK.examples[0]
    runner = RobotRunner(robot, RouteFollower(), TASK, operator=None, fps=None, max_steps=150)
    outcome = runner(context_for(instance))
    robot.disconnect()
    assert outcome.success and outcome.progress == 1.0 and outcome.extra["ended_by"] == "policy"
    assert outcome.scene_after.objects == instance.scene.objects  # the robot moved no furniture
    assert 0.7 < outcome.reference_length / outcome.path_length <= 1.0
    assert outcome.extra["ndtw"] > 0.5


def eval_flags(host, tmp_path, *flags: str) -> list[str]:
    ports = host.ports
    return [
        "--task=vln_paper", "--robot.type=locobot", f"--robot.port_command={ports['command']}",
        f"--robot.port_observation={ports['observation']}", f"--robot.port_rpc={ports['rpc']}",
        f"--robot.calibration_dir={tmp_path / 'calibration'}", "--robot.camera_width=320", "--robot.camera_height=240",
        "--policy.type=route_follower", "--max_episode_steps=150", f"--output_dir={tmp_path / 'run'}", *flags,
    ]  # fmt: skip


def journal(tmp_path) -> list[dict]:
    return [json.loads(line) for line in (tmp_path / "run" / "journal.jsonl").read_text().splitlines()]


def test_the_eval_cli_runs_a_vln_contrast_set_on_the_locobot_host(host, tmp_path):
    assert main(eval_flags(host, tmp_path, "--n_instances=1", "--perturbations=[L,SB]")) == 0
    records = journal(tmp_path)
    assert [r["perturbation"] for r in records] == [None, "L", "SB"]
    assert all(r["status"] == "done" and r["success"] and r["progress"] == 1.0 for r in records)
    assert all(r["extra"]["ndtw"] > 0.3 and 0 < r["spl"] <= 1 for r in records)
    assert records[1]["cost"] == 0.0 and records[2]["cost"] > 0.0  # ΔL is free, ΔSB moves furniture


@pytest.mark.slow
def test_the_shipped_contrast_evaluation_runs_its_75_trials(host, tmp_path):
    assert main(eval_flags(host, tmp_path, "--n_instances=5", "--repeats=3", "--rerun=false")) == 0
    records = journal(tmp_path)
    assert len(records) == 75 and all(r["status"] == "done" and r["success"] for r in records)


def test_a_host_that_dies_mid_trial_is_given_up_in_seconds_and_said_aborted(tmp_path, capsys):
    from lerobot_robot_locobot.config_host import SimConfig

    from lerobot_contrast.domains.vln.locobot_sim import SimBackend
    from tests.robots.locobot_helpers import DyingBackend

    backend = DyingBackend(SimBackend(SimConfig()), dies_at=5)
    thread = HostThread(FREE_PORTS, backend)
    backend.host_stop = thread.stop_event
    with thread as host:
        start = time.monotonic()
        flags = eval_flags(host, tmp_path, "--n_instances=1", "--perturbations=[L]", "--rerun=false", "--verbose=true")
        assert main(flags) == 2
        took = time.monotonic() - start
    out, err = capsys.readouterr()
    # 2 s of silence (60 periods at 30 Hz), then 5 s of reconnecting, each try waiting up to its connect timeout.
    assert took < 2 + 5 + 5 + 3, took
    assert "fell silent during step 5 (forward): no observation for 2 s); trying to reconnect for up to 5 s" in out
    assert "aborted: the robot disconnected after 4 steps" in out
    assert "[   2]" not in out and "0 not applicable, 1 aborted" in out  # the ΔL after it is not run, nor called n/a
    assert "could not reconnect within 5 s" in err
    assert [r["status"] for r in journal(tmp_path)] == ["aborted"]
    assert json.loads((tmp_path / "run" / "summary.json").read_text())["overall"]["aborted"] == 1


def test_an_unreachable_robot_is_one_line_and_leaves_no_run_directory(tmp_path, capsys):
    from lerobot_contrast.ports import free_port

    port = free_port()
    flags = ["--task=vln_paper", "--robot.type=locobot", f"--robot.port_rpc={port}", f"--robot.port_command={port}",
             "--robot.connect_timeout_s=0.5", "--policy.type=route_follower", f"--output_dir={tmp_path / 'run'}"]  # fmt: skip
    assert main(flags) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1 and "127.0.0.1" in err
    assert not (tmp_path / "run").exists()
