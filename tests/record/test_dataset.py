"""The run's LeRobotDataset: loads with LeRobot, carries the eval columns and sidecar, survives an interruption
and a resume, and plays with `lerobot-dataset-viz`."""

import dataclasses
import json
import shutil
import subprocess
import sys

import numpy as np
import pytest
from lerobot.datasets import LeRobotDataset

from lerobot_contrast.contrast.metrics import scored
from lerobot_contrast.contrast.trial import Outcome
from lerobot_contrast.record.dataset import DatasetError, DatasetRecorder
from tests.record.conftest import STEPS, read_rrd
from tests.record.lt_episodes import FEATURES, POSE_KEYS, Episodes, contexts

REPO_ID = "local/run"


def load(run_dir) -> LeRobotDataset:
    return LeRobotDataset(REPO_ID, root=run_dir / "dataset")


def journal(run_dir):
    return [json.loads(line) for line in (run_dir / "journal.jsonl").read_text().splitlines()]


def test_every_trial_is_an_episode_with_its_instruction_and_eval_columns(recorded_run):
    dataset, records = load(recorded_run), journal(recorded_run)
    assert dataset.num_episodes == len(records) and len(dataset) == STEPS * len(records)
    assert [r["dataset_episode"] for r in records] == list(range(len(records)))
    features = dataset.meta.features
    assert features["observation.state"]["names"] == [
        "effector.x",
        "effector.y",
        "effector_target.x",
        "effector_target.y",
    ]
    assert (
        features["action"]["names"] == ["delta_x", "delta_y"] and features["observation.images.top"]["dtype"] == "video"
    )
    for record in records:
        frames = [dataset[record["dataset_episode"] * STEPS + k] for k in range(STEPS)]
        first, last = frames[0], frames[-1]
        assert first["task"] == record["instance"]["instruction"]
        assert (first["eval.instance_id"], first["eval.base_id"]) == (record["instance"]["id"], record["base_id"])
        assert first["eval.perturbation"] == (record["perturbation"] or "original")
        assert int(first["eval.trial_index"]) == record["index"]
        assert [bool(f["next.success"]) for f in frames] == [False] * (STEPS - 1) + [record["success"]]
        assert [bool(f["next.done"]) for f in frames] == [False] * (STEPS - 1) + [True]
        assert tuple(last["observation.images.top"].shape) == (3, 180, 320)


def test_the_sidecar_maps_episodes_to_trials_costs_and_metrics(recorded_run):
    sidecar = recorded_run / "dataset" / "meta" / "contrast_eval"
    rows = [json.loads(line) for line in (sidecar / "episodes.jsonl").read_text().splitlines()]
    records = journal(recorded_run)
    assert [(r["episode_index"], r["trial_index"]) for r in rows] == [
        (r["dataset_episode"], r["index"]) for r in records
    ]
    assert [r["success"] for r in rows] == [r["success"] for r in records]
    assert [r["cost"] for r in rows] == [r["cost"] for r in records]
    assert rows[1]["perturbation"] == "LB1" and rows[1]["instance"]["goal"] == records[1]["instance"]["goal"]
    run = json.loads((sidecar / "run.json").read_text())
    assert run["episodes"] == len(records)
    assert json.loads((sidecar / "config.json").read_text()) == json.loads((recorded_run / "config.json").read_text())


def episode(recorder, episodes, context, steps=4, discard_after=None):
    observation = episodes.stage(context)
    recorder.start(context, FEATURES, POSE_KEYS)
    for k in range(steps):
        action = episodes.robot.send_action({"delta_x": 0.01, "delta_y": 0.0})
        recorder.step(k / 10, observation, action)
        observation = episodes.robot.get_observation()
        if k == discard_after:
            recorder.discard()
            return None
    outcome = Outcome(
        success=True, steps=steps, path_length=0.04, scene_after=episodes.robot.read_scene(), duration_s=0.4
    )
    return recorder.end(scored(context, outcome, 0.0, 0.0))


@pytest.mark.slow
def test_an_interrupted_run_resumes_appending_to_the_same_dataset_which_still_plays(tmp_path):
    episodes, trials = Episodes(), contexts(perturbations=("LB1", "SB1"))
    first = DatasetRecorder(tmp_path, fps=10, repo_id=REPO_ID)
    assert episode(first, episodes, trials[0]).dataset_episode == 0
    episode(first, episodes, trials[1], discard_after=1)  # the operator redid the trial, then Ctrl-C
    first.close()
    assert load(tmp_path).num_episodes == 1
    resumed = DatasetRecorder(tmp_path, fps=10, repo_id=REPO_ID)
    assert [episode(resumed, episodes, t).dataset_episode for t in trials[1:]] == [1, 2]
    resumed.close()
    dataset = load(tmp_path)
    assert dataset.num_episodes == 3 and len(dataset) == 12
    assert [int(dataset[k]["eval.trial_index"]) for k in (0, 4, 8)] == [0, 1, 2]
    assert dataset[4]["task"] == trials[1].instance.instruction
    out = tmp_path / "viz"
    result = subprocess.run(
        [sys.executable, "-m", "lerobot.scripts.lerobot_dataset_viz", "--repo-id", REPO_ID, "--root",
         str(tmp_path / "dataset"), "--episode-index", "2", "--save", "1", "--output-dir", str(out), "--num-workers", "0"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr[-2000:]
    (saved,) = out.glob("*.rrd")
    _, chunks = read_rrd(saved)
    assert sum(c.num_rows for c in chunks["/observation.images.top"]) == 4
    assert any(path.startswith("/next.success") for path in chunks)


def test_resuming_with_other_robot_features_is_refused(tmp_path):
    episodes, (context,) = Episodes(), contexts(perturbations=())
    recorder = DatasetRecorder(tmp_path, fps=10)
    episode(recorder, episodes, context)
    recorder.close()
    other = {"observation": {**FEATURES["observation"], "wrist": (180, 320, 3)}, "action": FEATURES["action"]}
    resumed = DatasetRecorder(tmp_path, fps=10)
    with pytest.raises(DatasetError, match="other robot features"):
        resumed.start(context, other, POSE_KEYS)
    resumed.close()


def test_a_dataset_created_but_never_given_an_episode_starts_afresh(tmp_path):
    episodes, (context,) = Episodes(), contexts(perturbations=())
    recorder = DatasetRecorder(tmp_path, fps=10)
    episode(recorder, episodes, context, discard_after=0)
    recorder.close()
    again = DatasetRecorder(tmp_path, fps=10, repo_id=REPO_ID)
    assert episode(again, episodes, context).dataset_episode == 0
    again.close()
    assert load(tmp_path).num_episodes == 1


def test_an_episode_without_steps_stores_nothing(tmp_path):
    (context,) = contexts(perturbations=())
    recorder = DatasetRecorder(tmp_path, fps=10)
    recorder.start(context, FEATURES, POSE_KEYS)
    files = recorder.end(scored(context, Outcome(True, 0, 0.0, context.instance.scene, 0.0), 0.0, 0.0))
    recorder.close()
    assert files.dataset_episode is None
    assert json.loads((tmp_path / "dataset" / "meta" / "info.json").read_text())["total_episodes"] == 0


def test_a_long_episode_is_handed_to_lerobot_in_batches_without_changing_the_dataset(tmp_path):
    episodes, (context,) = Episodes(), contexts(perturbations=())
    frame_mb = 180 * 320 * 3 / 2**20
    recorder = DatasetRecorder(tmp_path, fps=10, repo_id=REPO_ID, max_buffer_mb=2.5 * frame_mb)
    episode(recorder, episodes, context, steps=7)
    recorder.close()
    dataset = load(tmp_path)
    assert dataset.num_episodes == 1 and [int(dataset[k]["frame_index"]) for k in range(7)] == list(range(7))
    assert [bool(dataset[k]["next.success"]) for k in range(7)] == [False] * 6 + [True]


@pytest.mark.slow
def test_a_run_killed_mid_episode_keeps_every_finished_episode(tmp_path):
    code = (
        "import os, sys\n"
        "from tests.record.lt_episodes import Episodes, contexts\n"
        "from tests.record.test_dataset import REPO_ID, episode\n"
        "from lerobot_contrast.record.dataset import DatasetRecorder\n"
        "episodes, trials = Episodes(), contexts(perturbations=('LB1', 'SB1'))\n"
        "recorder = DatasetRecorder(sys.argv[1], fps=10, repo_id=REPO_ID)\n"
        "episode(recorder, episodes, trials[0])\n"
        "episode(recorder, episodes, trials[1])\n"
        "recorder.step = lambda *args, real=recorder.step: (real(*args), os._exit(9))\n"
        "episode(recorder, episodes, trials[2])\n"
    )
    killed = subprocess.run([sys.executable, "-c", code, str(tmp_path)], capture_output=True, text=True, timeout=300)
    assert killed.returncode == 9, killed.stderr[-2000:]
    assert load(tmp_path).num_episodes == 2  # readable as left, without close()
    episodes, trials = Episodes(), contexts(perturbations=("LB1", "SB1"))
    resumed = DatasetRecorder(tmp_path, fps=10, repo_id=REPO_ID)
    assert episode(resumed, episodes, trials[2]).dataset_episode == 2
    resumed.close()
    dataset = load(tmp_path)
    assert dataset.num_episodes == 3 and [int(dataset[k]["eval.trial_index"]) for k in (0, 4, 8)] == [0, 1, 2]


def test_a_dataset_damaged_while_saving_is_refused_with_advice_not_fetched_from_the_hub(tmp_path):
    episodes, (context,) = Episodes(), contexts(perturbations=())
    recorder = DatasetRecorder(tmp_path, fps=10)
    episode(recorder, episodes, context)
    recorder.close()
    shutil.rmtree(tmp_path / "dataset" / "meta" / "episodes")
    resumed = DatasetRecorder(tmp_path, fps=10)
    with pytest.raises(DatasetError, match="is damaged .*; restore it from a copy"):
        resumed.start(context, FEATURES, POSE_KEYS)
    resumed.close()


def flat_stats(run_dir) -> dict[str, np.ndarray]:
    stats = json.loads((run_dir / "dataset" / "meta" / "stats.json").read_text())
    return {
        f"{feature}/{name}": np.asarray(value) for feature, values in stats.items() for name, value in values.items()
    }


def test_rollback_to_the_journal_drops_later_episodes_and_the_dataset_loads_as_before(tmp_path):
    episodes, trials = Episodes(), contexts(perturbations=("LB1", "SB1"))
    recorder = DatasetRecorder(tmp_path, fps=10, repo_id=REPO_ID)
    files = [episode(recorder, episodes, trial) for trial in trials[:2]]
    recorder.close()
    before = {name: (tmp_path / "dataset" / "meta" / name).read_bytes() for name in ("info.json", "tasks.parquet")}
    frames = load(tmp_path).hf_dataset.select_columns(["index", "eval.trial_index", "action"]).to_list()
    stats = flat_stats(tmp_path)
    again = DatasetRecorder(tmp_path, fps=10, repo_id=REPO_ID)
    assert episode(again, episodes, trials[2]).dataset_episode == 2  # saved, but its trial never journaled
    again.close()
    journaled = [scored(trial, Outcome(True, 4, 0.04, trial.instance.scene, 0.4), 0.0, 0.0) for trial in trials[:2]]
    journaled = [
        dataclasses.replace(r, dataset_episode=f.dataset_episode) for r, f in zip(journaled, files, strict=True)
    ]
    resumed = DatasetRecorder(tmp_path, fps=10, repo_id=REPO_ID)
    resumed.rollback(journaled)
    assert {name: (tmp_path / "dataset" / "meta" / name).read_bytes() for name in before} == before
    assert flat_stats(tmp_path).keys() == stats.keys()
    assert all(np.allclose(flat_stats(tmp_path)[key], value, rtol=1e-6) for key, value in stats.items())
    assert load(tmp_path).hf_dataset.select_columns(["index", "eval.trial_index", "action"]).to_list() == frames
    sidecar = (tmp_path / "dataset" / "meta" / "contrast_eval" / "episodes.jsonl").read_text().splitlines()
    assert [json.loads(line)["episode_index"] for line in sidecar] == [0, 1]
    assert episode(resumed, episodes, trials[2]).dataset_episode == 2
    resumed.close()
    assert load(tmp_path).num_episodes == 3


def test_a_journal_naming_episodes_the_dataset_lacks_is_refused_with_advice(tmp_path):
    episodes, (context,) = Episodes(), contexts(perturbations=())
    recorder = DatasetRecorder(tmp_path, fps=10, repo_id=REPO_ID)
    files = episode(recorder, episodes, context)
    recorder.close()
    record = scored(context, Outcome(True, 4, 0.04, context.instance.scene, 0.4), 0.0, 0.0)
    named = [dataclasses.replace(record, dataset_episode=files.dataset_episode + 1)]
    with pytest.raises(
        DatasetError, match=r"holds 1 complete episodes of the first 2 that the journal names; restore it"
    ):
        DatasetRecorder(tmp_path, fps=10, repo_id=REPO_ID).rollback(named)
