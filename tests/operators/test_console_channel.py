"""The person at the console speaks the operator interface, and its structured channel says each prompt as JSON,
so a program answers it without reading the screen."""

import io
import json
import os
import subprocess
import sys

import numpy as np
import pytest
from rich.console import Console

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.task import Judgement
from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.domains import load_task
from lerobot_contrast.operators.base import Operator
from lerobot_contrast.operators.channel import Channel, parse
from lerobot_contrast.operators.console import Answers, OperatorConsole
from lerobot_contrast.twin.console_session import Lines


def console(answers: str, channel_path=None) -> OperatorConsole:
    channel = None if channel_path is None else Channel(channel_path)
    return OperatorConsole(Answers(io.StringIO(answers)), Console(file=io.StringIO()), channels=[channel])


def context() -> TrialContext:
    task = load_task("so101_blocks")
    instance = task.sample(1, np.random.default_rng(0))[0]
    start = Scene({name: Pose(pose.x, pose.y - 0.05) for name, pose in instance.scene.objects.items()})
    return TrialContext(0, instance, instance, start, 0.15, "reset", np.random.default_rng(0), 3)


def test_the_console_is_an_operator():
    operator: Operator = console("")
    for method in ("stage", "fix_or_accept", "running", "take_key", "label", "aborted", "say"):
        assert callable(getattr(operator, method))
    assert operator.bench is None


def test_each_prompt_goes_to_the_channel_as_one_json_line(tmp_path):
    path = tmp_path / "channel.jsonl"
    operator = console("\na\ny\nq\n", path)
    trial = context()
    assert operator.stage(trial).action == "ready"
    assert operator.fix_or_accept({"red_cube": 0.041, "green_cube": None}, 0.02) == "accept"
    operator.running()
    label = operator.label([], Judgement(success=False), None)
    assert label.action == "done" and label.success
    assert operator.aborted("emergency stop").action == "stop"
    messages = [parse(line) for line in path.read_text().splitlines()]
    assert [m.get("prompt", m.get("event")) for m in messages] == [
        "trial",
        "stage",
        "check",
        "running",
        "label",
        "aborted",
    ]
    assert messages[0]["moves"] == messages[1]["moves"]
    assert Instance.from_json(messages[0]["instance"]) == trial.instance  # what runs, for a judge to judge by
    messages = messages[1:]
    stage = messages[0]
    assert stage["trial"] == 0 and stage["of"] == 3 and stage["instruction"] == trial.instance.instruction
    targets = trial.instance.scene.objects
    assert stage["moves"] == {name: [targets[name].x, targets[name].y] for name in stage["moves"]}
    assert set(stage["moves"]) == set(targets)  # every object was 5 cm off
    assert messages[1]["off"] == {"red_cube": 0.041, "green_cube": None}
    assert messages[3]["instruction"] == trial.instance.instruction and messages[3]["subgoals"] == []
    assert messages[4]["reason"] == "emergency stop"


def test_a_line_that_is_not_a_message_is_ignored():
    assert parse("not json") is None
    assert parse(json.dumps({"version": 99, "prompt": "stage"})) is None
    assert parse(json.dumps({"version": 1, "prompt": "stage"})) == {"version": 1, "prompt": "stage"}


def test_a_channel_that_cannot_be_opened_is_one_line(tmp_path):
    with pytest.raises(Exception, match=r"--operator_channel=.*nowhere.*: cannot open it"):
        Channel(tmp_path / "nowhere" / "channel.jsonl")


def test_lines_keeps_a_partial_line_until_it_ends():
    read_end, write_end = os.pipe()
    lines = Lines(read_end)
    os.write(write_end, b'{"a": 1}\n{"b"')
    assert lines.read() == ['{"a": 1}']
    os.write(write_end, b": 2}\n")
    assert lines.read() == ['{"b": 2}']
    os.close(write_end)
    assert lines.read() == [] and lines.closed
    os.close(read_end)


def test_the_scripted_persons_bad_flags_are_one_line():
    command = [sys.executable, "-m", "lerobot_contrast.twin.operator", "--seed=abc", "--task=so101_blocks"]
    done = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == ["error: argument --seed: invalid int value: 'abc'"]
    command[3] = "--on_flagged=sometimes"
    done = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
