"""A faulty serial line under the evaluator: LeRobot's retries or one clear line, never a traceback or a silent wrong
action."""

import json
import subprocess
import sys

import pytest

from lerobot_contrast.ports import free_port
from lerobot_contrast.so101 import arm
from lerobot_contrast.twin.bus_server import BusServer
from lerobot_contrast.twin.calibration_file import write_calibration_file
from lerobot_contrast.twin.faults import FaultsConfig
from lerobot_contrast.twin.servos import ServoBank
from tests.twin.test_eval_on_twin import Twin, operator, save_so101_act


@pytest.fixture
def bench(tmp_path):
    """Start the arm's bus with the given faults; returns the eval flags that reach it."""
    started = []

    def start(faults: FaultsConfig) -> list[str]:
        bank = ServoBank(arm.MOTORS, arm.rest_raw(), limits=arm.raw_limits())
        write_calibration_file(bank, "twin", tmp_path)
        server = BusServer(bank, faults, clocked=True)
        started.append(server)
        port = server.start()
        return ["--robot.type=so101_follower", f"--robot.port={port}", "--robot.id=twin",
                f"--robot.calibration_dir={tmp_path}"]  # fmt: skip

    yield start
    for server in started:
        server.stop()


def evaluate(flags: list[str], answers: str) -> subprocess.CompletedProcess:
    command = [sys.executable, "-m", "lerobot_contrast.eval", "--task=so101_blocks", "--operator=console", *flags]
    return subprocess.run(command, input=answers, capture_output=True, text=True, timeout=300)


def test_a_bus_that_never_answers_is_one_line_and_leaves_no_run(bench, tmp_path):
    flags = bench(FaultsConfig(drop=1.0))
    done = evaluate([*flags, f"--output_dir={tmp_path / 'run'}"], "")
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0 and "Traceback" not in done.stderr
    assert "cannot connect" in done.stderr and "motor check failed" in done.stderr
    assert not (tmp_path / "run").exists()


@pytest.mark.realtime
@pytest.mark.slow
def test_reads_that_fail_past_lerobots_retries_abort_the_trial_with_lerobots_reason(tmp_path):
    policy = save_so101_act(tmp_path / "act")
    twin = Twin(tmp_path / "calibration", free_port(), free_port(), "--faults.corrupt=1", "--faults.while_moving=true")
    try:  # a clean line until the arm moves, then every status packet corrupted
        run = tmp_path / "run"
        flags = [*twin.flags, f"--policy.path={policy}", "--policy.device=cpu", "--max_episode_s=2"]
        answering = operator(twin, "--task=so101_blocks", "--n_instances=1", "--strategy=standard", *flags,
                             f"--output_dir={run}")  # fmt: skip
        said = answering.communicate(timeout=300)[0]
    finally:
        twin.stop()
    assert "Traceback" not in said
    assert "disconnected (Failed to sync read 'Present_Position'" in said and "Incorrect status packet" in said, said
    records = [json.loads(line) for line in (run / "journal.jsonl").read_text().splitlines()]
    assert records[0]["status"] == "aborted" and records[0]["extra"]["ended_by"] == "disconnected"
