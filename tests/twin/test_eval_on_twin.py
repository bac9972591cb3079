"""The evaluator on the virtual SO-101, as on the arm: `python -m lerobot_contrast.twin` in one process, the scripted
operator answering `python -m lerobot_contrast.eval --operator=console` in another, LeRobot's so101_follower and zmq
camera between them. The policy under test is a random-weight ACT made for the SO-101's features."""

import json
import os
import shlex
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.ports import free_port
from lerobot_contrast.twin.operator import Operator, OperatorError, PlacementError, Plan

FRAME = ("--width=160", "--height=120")  # a small camera keeps the test quick; the bench times 640x480
RUN = ("--task=so101_blocks", "--strategy=contrast", "--n_instances=1", "--perturbations=L,S1", "--fps=30")


class Twin:
    """The twin process; `flags` are the eval flags it printed, `placement` its placement socket."""

    def __init__(self, calibration_dir: Path, camera: int, control: int, *flags: str):
        command = [sys.executable, "-m", "lerobot_contrast.twin", f"--calibration_dir={calibration_dir}",
                   f"--camera_port={camera}", f"--control_port={control}", *FRAME, *flags]  # fmt: skip
        self.process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.placement = f"tcp://127.0.0.1:{control}"
        seen = []
        for line in self.process.stdout:
            seen.append(line)
            if line.startswith("eval flags: "):
                self.flags = shlex.split(line.removeprefix("eval flags: "))
                return
        raise AssertionError(f"the twin did not start: {''.join(seen)}")

    def kill(self) -> None:
        self.process.kill()
        self.process.wait()

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            self.process.wait(timeout=30)


def save_so101_act(directory: Path) -> Path:
    """A random-weight ACT for the SO-101's six joints and the twin's `front` camera at the tests' frame size."""
    from lerobot.cameras.zmq import ZMQCameraConfig
    from lerobot.robots.so_follower import SO101Follower, SO101FollowerConfig

    from lerobot_contrast.policies.pretrained import save_fresh_policy
    from tests.lerobot_helpers import SMALL_ACT

    camera = ZMQCameraConfig(server_address="127.0.0.1", port=5555, camera_name="front", width=160, height=120, fps=30)
    config = SO101FollowerConfig(port="unused", id="act", calibration_dir=directory / "calibration",
                                 cameras={"front": camera})  # fmt: skip
    return save_fresh_policy(SO101Follower(config), "act", directory, device="cpu", **SMALL_ACT)


@pytest.fixture
def policy(tmp_path) -> Path:
    return save_so101_act(tmp_path / "act")


def operator(twin: Twin, *flags: str) -> subprocess.Popen:
    command = [sys.executable, "-m", "lerobot_contrast.twin.operator", f"--placement={twin.placement}", *flags]
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)


def journal(run_dir: Path) -> list[dict]:
    return [json.loads(line) for line in (run_dir / "journal.jsonl").read_text().splitlines()]


@pytest.mark.realtime
@pytest.mark.slow
def test_a_contrast_set_runs_on_the_twin_and_a_killed_twin_resumes_with_nothing_lost(tmp_path, policy):
    run_dir = tmp_path / "run"
    ports = free_port(), free_port()  # a restarted twin keeps its camera's port: only the serial port is new
    twin = Twin(tmp_path / "calibration", *ports)
    try:
        flags = [*RUN, *twin.flags, f"--policy.path={policy}", "--policy.device=cpu", "--max_episode_s=2"]
        answering = operator(twin, "--placement_error=normal:0.005", *flags, f"--output_dir={run_dir}")
        said = []
        for line in answering.stdout:
            said.append(line)
            if line.startswith("running ·"):
                twin.kill()  # mid-episode: the arm loses power
        answering.wait(timeout=120)
        output = "".join(said)
        assert "[operator] Enter" in output  # staged through the placement socket
        assert "aborted: the robot disconnected after" in output, output
        assert f"--output_dir={run_dir} --resume=true" in output
        assert [r["status"] for r in journal(run_dir)] == ["aborted"]
    finally:
        twin.stop()
    twin = Twin(tmp_path / "calibration", *ports)
    try:
        port = next(flag for flag in twin.flags if flag.startswith("--robot.port="))
        resume = [f"--output_dir={run_dir}", "--resume=true", "--robot.type=so101_follower", port]
        resumed = operator(twin, *resume)
        output = resumed.communicate(timeout=300)[0]
        assert resumed.returncode == 0, output
        records = journal(run_dir)
        assert [(r["index"], r["status"]) for r in records] == [(0, "done"), (1, "done"), (2, "done")], output
        answers = [
            line.removeprefix("[operator] ") for line in output.splitlines() if line in ("[operator] y", "[operator] n")
        ]
        assert [bool(r["success"]) for r in records] == [a == "y" for a in answers]
    finally:
        twin.stop()


class FakePlacement:
    """The twin's placement socket, as the operator sees it: where it put things, and a scene to report."""

    def __init__(self, scene: Scene):
        self.placed, self.reported = {}, scene
        self.z = dict.fromkeys(scene.objects, 0.0125)  # resting on the table
        self.gripped: set[str] = set()  # touching the jaws

    def place(self, name: str, x: float, y: float) -> None:
        self.placed[name] = (x, y)

    def scene(self) -> Scene:
        return self.reported

    def look(self) -> tuple[Scene, dict[str, float], frozenset[str]]:
        return self.scene(), dict(self.z), frozenset(self.gripped)


def planned_trials() -> dict[int, Instance]:
    """The trials of RUN as the evaluator plans them: what its channel says it runs."""
    from lerobot_contrast.spine.config import EvalConfig
    from lerobot_contrast.spine.evaluation import preview
    from lerobot_contrast.spine.flags import parse_config
    from lerobot_contrast.spine.run_setup import planned_evaluation

    planned = planned_evaluation(parse_config(EvalConfig, [*RUN, "--robot.type=so101_follower", "--robot.port=unused"]))
    return {r.index: r.instance for r in preview(planned) if r.instance is not None}


def started(index: int, instance: Instance) -> dict:
    """The channel's event at a trial's start."""
    return {"event": "trial", "trial": index, "instruction": instance.instruction, "instance": instance.to_json()}


INSTRUCTION = "put the red cube next to the green cube"
STAGE = {"prompt": "stage", "trial": 0, "of": 3, "instruction": INSTRUCTION,
         "moves": {"green_cube": [0.320, -0.041], "red_cube": [0.269, 0.057]}}  # fmt: skip
CHECK = {"prompt": "check", "off": {"red_cube": 0.041, "green_cube": 0.0}, "tolerance": 0.02}
LABEL = {"prompt": "label", "trial": 0, "instruction": INSTRUCTION, "subgoals": []}
CHANNEL = [STAGE, CHECK, {"event": "running"}, LABEL]  # what the console's channel says of one trial


@pytest.mark.parametrize(("red", "label"), [((0.30, -0.02), "y"), ((0.20, 0.20), "n")])
def test_the_operator_places_what_the_console_says_and_labels_from_the_true_scene(red, label):
    plan = Plan([*RUN, "--robot.type=so101_follower", "--robot.port=unused"])
    truth = Scene({"red_cube": Pose(*red), "green_cube": Pose(0.32, -0.041), "blue_cube": Pose(0.39, 0.07)})
    placement = FakePlacement(truth)
    scripted = Operator(plan, placement, PlacementError.parse("none"), seed=0, on_flagged="fix")
    first = planned_trials()[0]
    assert first.instruction == INSTRUCTION
    channel = [started(0, first), *CHANNEL]
    typed = [answer for message in channel if (answer := scripted.handle(message)) is not None]
    assert typed == ["", "", label]  # staged, the flagged cube placed again, the label the scene shows
    assert placement.placed == {"green_cube": (0.320, -0.041), "red_cube": (0.269, 0.057)}


class MovingPlacement(FakePlacement):
    """A placement socket whose scene follows what is placed, as the twin's does."""

    def place(self, name: str, x: float, y: float) -> None:
        super().place(name, x, y)
        self.reported = Scene({**self.reported.objects, name: Pose(x, y)})


def test_what_the_robot_moved_and_the_console_says_to_leave_is_put_back_and_reported():
    plan = Plan([*RUN, "--robot.type=so101_follower", "--robot.port=unused"])
    second = planned_trials()[1]
    start = second.scene.objects  # the ΔL trial starts from the base's scene
    in_bin = Pose(0.30, 0.18)  # where the base's trial left the red cube: no camera told the console
    placement = MovingPlacement(Scene({**start, "red_cube": in_bin}))
    scripted = Operator(plan, placement, PlacementError.parse("none"), seed=0, on_flagged="accept")
    stage = {"prompt": "stage", "trial": 1, "of": 3, "instruction": second.instruction, "moves": {}}
    typed = [scripted.handle(message) for message in (started(1, second), stage)][1:]
    back = start["red_cube"]
    assert placement.placed == {"red_cube": pytest.approx((back.x, back.y))}
    assert typed == [f"c {in_bin.distance_to(back):.3f}"]  # the metres moved, as a person types them


def test_a_cube_still_held_over_its_goal_when_the_episode_ends_is_a_failure():
    plan = Plan([*RUN, "--robot.type=so101_follower", "--robot.port=unused"])
    first = planned_trials()[0]
    start = first.scene.objects
    placement = FakePlacement(Scene(dict(start)))
    scripted = Operator(plan, placement, PlacementError.parse("none"), seed=0, on_flagged="accept")
    typed = [scripted.handle(message) for message in (started(0, first), STAGE, CHECK)][1:]
    assert typed == ["", "a"]  # staged, and what the camera flagged accepted
    green = start["green_cube"]  # the goal holds by x and y: the red cube hangs right beside the green one
    placement.reported = Scene({**start, "red_cube": Pose(green.x + 0.04, green.y)})
    placement.z["red_cube"] += 0.06  # ... 6 cm up, on top of something: not held, it lies there
    assert scripted.handle(LABEL) == "y"
    placement.gripped.add("red_cube")  # ... in the gripper
    assert scripted.handle(LABEL) == "n"
    assert scripted.said[-1] == "red_cube is held 6.0 cm up, not put down"
    ended = next(line for line in scripted.said if line.startswith("the trial ended with "))
    assert f"red_cube ({green.x + 0.04:.3f}, {green.y:.3f})" in ended  # where each object is, for the study's log
    placement.z["red_cube"] -= 0.06  # let go: now it rests there
    placement.gripped.clear()
    assert scripted.handle(LABEL) == "y"


def test_the_operators_bad_input_is_one_line():
    with pytest.raises(OperatorError, match="--placement_error=uniform:1: give none, normal:SIGMA or offset:D"):
        PlacementError.parse("uniform:1")
    offset = PlacementError.parse("offset:0.04")
    dx, dy = offset.draw(np.random.default_rng(0))
    assert abs((dx**2 + dy**2) ** 0.5 - 0.04) < 1e-12
