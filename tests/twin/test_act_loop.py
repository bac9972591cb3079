"""The LeRobot user's own loop on the virtual SO-101, through LeRobot's own commands: `lerobot-record` with the
scripted demonstrator, `lerobot-train --policy.type=act`, then a contrast-set evaluation of the checkpoint (and of the
demonstrator, which reads the words) with the scripted operator at the console."""

import json
import subprocess
import sys

import pytest

from lerobot_contrast.domains.task_file import load_task_file
from lerobot_contrast.ports import free_port
from lerobot_contrast.so101 import arm, plan
from lerobot_contrast.twin.launch import start_twin
from tests.study_scripts import load_script, script_path

INSTRUCTION = "put the red cube in the left bin"


@pytest.mark.parametrize(
    ("script", "flags", "said"),
    [
        ("record_so101_demos", ["--output=demos", "--episodes=0"], "--episodes must be at least 1"),
        (
            "record_so101_demos",
            ["--output=demos", "--episodes=2", "--shards=3"],
            "--shards=3: give from 1 to --episodes",
        ),
        (
            "train_so101_act",
            ["--dataset=nowhere", "--output=act"],
            "--dataset=nowhere holds no LeRobot dataset; record",
        ),
        ("train_so101_act", ["--dataset=d", "--output=act", "--steps=0"], "--steps, --batch_size and --save_freq must"),
        ("train_so101_act", ["--output=act"], "the following arguments are required: --dataset"),
        ("study_so101_act", ["--output=s", "--policies=foo"], "--policies: foo; choose from act,demonstrator"),
        ("study_so101_act", ["--output=s", "--policies=act"], "--policies=act needs --checkpoint: lerobot-train's"),
        ("study_so101_act", ["--output=s", "--checkpoint=nowhere"], "--checkpoint=nowhere holds no config.json"),
        ("study_so101_act", ["--output=s", "--n_instances=0"], "--n_instances must be at least 1"),
        ("study_so101_act", ["--output=s", "--policies=ab", "--checkpoint=."], "--checkpoint=. holds no config.json"),
    ],
)
def test_the_loops_scripts_answer_bad_flags_in_one_line(script, flags, said, tmp_path):
    done = subprocess.run([sys.executable, script_path(script), *flags], capture_output=True, text=True,
                          cwd=tmp_path, timeout=120)  # fmt: skip
    assert done.returncode == 2 and done.stderr.startswith(f"error: {said}"), done.stderr
    assert done.stderr.count("\n") == 1


@pytest.mark.realtime
@pytest.mark.slow
def test_record_train_act_and_evaluate_it_on_the_twin(tmp_path):
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    record = load_script("record_so101_demos")
    demos = tmp_path / "demos"
    shape = ["--episodes=2", "--reset_time_s=0.5", "--episode_time_s=8", "--pace=1", "--width=96", "--height=72",
             "--seed=5"]  # fmt: skip
    args = record.parse_args([f"--output={demos}", *shape])
    twin = start_twin(f"--calibration_dir={tmp_path}", f"--camera_port={free_port()}", f"--control_port={free_port()}",
                      "--width=96", "--height=72", "--seed=5")  # fmt: skip
    try:
        assert record.record(args, twin, demos, 0, 2) is None
        from lerobot_contrast.twin.placement_client import request

        scene = request({"cmd": "scene"}, int(twin.placement.rsplit(":", 1)[1]))["objects"]
    finally:
        twin.stop()
    dataset = LeRobotDataset(record.REPO_ID, root=demos)
    assert dataset.num_episodes == 2 and dataset.meta.robot_type == "so_follower"
    assert dataset.features["action"]["names"] == [f"{name}.pos" for name in arm.MOTOR_NAMES]
    assert dataset.features["observation.images.front"]["shape"] == (72, 96, 3)
    assert dataset[0]["task"] == INSTRUCTION
    # The second episode's cubes were placed in the reset period: the ones left alone lie where its placement put them.
    second = plan.placement(load_task_file("so101_blocks").spec, 5, 1)
    for name in ("green_cube", "blue_cube"):
        assert scene[name][:2] == pytest.approx(second[name][:2], abs=0.01)
    # The same episodes recorded by two twins side by side, one each, then joined: each keeps its placement and place.
    sharded = tmp_path / "sharded"
    assert record.main([f"--output={sharded}", "--shards=2", *shape]) == 0
    joined = LeRobotDataset(record.REPO_ID, root=sharded)
    assert joined.num_episodes == 2 and not record.shard_root(sharded).exists()

    def first_frame(data, episode):
        return data[data.meta.episodes["dataset_from_index"][episode]]["observation.images.front"]

    for episode in (0, 1):
        own = (first_frame(joined, episode) - first_frame(dataset, episode)).abs().mean()
        other = (first_frame(joined, episode) - first_frame(dataset, 1 - episode)).abs().mean()
        assert own < other, (episode, own, other)

    train = load_script("train_so101_act")
    flags = [f"--dataset={demos}", f"--output={tmp_path / 'act'}", "--batch_size=2", "--save_freq=2", "--num_workers=0"]
    assert train.main([*flags, "--steps=2"]) == 0
    assert train.main([*flags, "--steps=3"]) == 0  # trains on from the last checkpoint, as after a kill
    assert train.trained_steps(tmp_path / "act") == 3
    checkpoint = train.last_checkpoint(tmp_path / "act")
    config = json.loads((checkpoint / "config.json").read_text())
    assert config["type"] == "act" and config["input_features"]["observation.images.front"]["shape"] == [3, 72, 96]

    study = load_script("study_so101_act")
    out = tmp_path / "study"
    assert study.main([f"--checkpoint={checkpoint}", f"--output={out}", "--n_instances=1", "--max_episode_s=1"]) == 0
    for policy in ("act", "demonstrator"):
        records = [json.loads(line) for line in (out / policy / "journal.jsonl").read_text().splitlines()]
        assert [r["status"] for r in records] == ["done"] * len(records) and len(records) >= 4
        assert (
            records[0]["instance"]["instruction"] == INSTRUCTION
        )  # the base says the recorded task; its perturbations follow
        assert {r["perturbation"] for r in records[1:]} >= {"L", "LB2", "LB3", "SB"}
    assert "ΔLB3" in (out / "report" / "report.md").read_text()
    ended = (out / "report" / "where_it_ended.md").read_text()  # from each run's log of the operator's view
    assert "## act" in ended and "## demonstrator" in ended and "| original | 1 |" in ended

    # Two checkpoints of one training (2 and 3 steps), interleaved on the same bases, as after a second round of data.
    first = tmp_path / "act" / "checkpoints" / "000002" / "pretrained_model"
    flags = [f"--checkpoint={first}", f"--compare={checkpoint}", "--policies=ab", "--n_instances=1"]
    assert study.main([*flags, f"--output={out}", "--max_episode_s=1"]) == 0
    pairs = json.loads((out / "ab" / "pairs.json").read_text())
    assert len(pairs["policies"]) == 2
    assert (out / "ab" / "report" / "report.md").is_file()
