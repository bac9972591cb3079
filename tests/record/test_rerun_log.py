"""Per-episode Rerun recordings, checked with Rerun's own CLI and reader: files, entities, timelines, frames,
properties, the scene map and the perturbation text."""

import dataclasses
import json
import os
import shutil
from types import SimpleNamespace

import numpy as np
import pytest
import rerun as rr

from lerobot_contrast.contrast.metrics import scored
from lerobot_contrast.contrast.trial import Outcome
from lerobot_contrast.record.rerun_log import APPLICATION_ID, LAYOUT_FILE, RerunEpisodeRecorder, RerunWriteError
from tests.record.conftest import STEPS, read_rrd, rerun_cli, static_row
from tests.record.lt_episodes import FEATURES, POSE_KEYS, Episodes, contexts


def journal(run_dir):
    return [json.loads(line) for line in (run_dir / "journal.jsonl").read_text().splitlines()]


def test_every_episode_is_one_verified_rrd_file_named_by_its_trial(recorded_run):
    records = journal(recorded_run)
    paths = [recorded_run / r["rerun_path"] for r in records]
    assert [p.name for p in paths] == [f"episode_{r['index']:06d}.rrd" for r in records]
    assert sorted(p.name for p in (recorded_run / "rerun").iterdir()) == sorted([*(p.name for p in paths), LAYOUT_FILE])
    result = rerun_cli("rrd", "verify", *map(str, paths))
    assert result.returncode == 0, result.stderr
    assert f"{len(paths)} files verified without error" in result.stdout + result.stderr


def test_a_recording_holds_the_streams_on_frame_and_time_timelines(recorded_run):
    record = journal(recorded_run)[1]
    reader, chunks = read_rrd(recorded_run / record["rerun_path"])
    (store,) = reader.recordings()
    assert store.application_id == APPLICATION_ID and store.recording_id.endswith("-trial000001")
    assert len(reader.blueprints()) == 1  # the default layout travels with the file
    for entity in ("/camera/top", "/action", "/state", "/map/robot"):
        temporal = [c for c in chunks[entity] if not c.is_static]
        assert sum(c.num_rows for c in temporal) == STEPS, entity
        assert all(set(c.timeline_names) == {"frame", "time"} for c in temporal)
    for entity in ("/map/objects", "/map/objects_after", "/map/goal", "/map/path", "/instruction", "/outcome"):
        assert any(c.is_static for c in chunks[entity]), entity
    (actions,) = [c for c in chunks["/action"] if not c.is_static]
    values = np.array(actions.to_record_batch().column("Scalars:scalars").to_pylist())
    assert values.shape == (STEPS, 2) and np.abs(values).max() <= 0.1
    assert static_row(chunks["/action"])["names"] == ["delta_x", "delta_y"]


def test_properties_name_the_instance_perturbation_policy_and_metrics(recorded_run):
    record = journal(recorded_run)[1]
    _, chunks = read_rrd(recorded_run / record["rerun_path"])
    trial = static_row(chunks["/__properties/eval"])
    assert trial["instance_id"] == record["instance"]["id"] and trial["base_id"] == record["base_id"]
    assert (trial["perturbation"], trial["perturbation_label"], trial["axis"]) == ("LB1", "ΔLB1", "LB")
    assert (trial["strategy"], trial["policy"], trial["trial_index"]) == ("contrast", "oracle", 1)
    metric = static_row(chunks["/__properties/metric"])
    assert metric["success"] == record["success"] and metric["steps"] == STEPS
    assert metric["progress"] == float(record["success"]) and 0.0 <= metric["spl"] <= 1.0


def test_the_text_says_what_the_perturbation_changed(recorded_run):
    original, swapped, moved = journal(recorded_run)[:3]
    texts = {}
    for record in (original, swapped, moved):
        _, chunks = read_rrd(recorded_run / record["rerun_path"])
        texts[record["index"]] = static_row(chunks["/instruction"])["text"]
        assert ("/map/base_changes" in chunks) == (record is moved)
    assert "none (an i.i.d. instance)" in texts[0] and "nothing: this is the base instance" in texts[0]
    assert "ΔLB1, axis ΔLB (new wording, different behaviour): swap the source" in texts[1]
    assert f"“{original['instance']['instruction']}” → “{swapped['instance']['instruction']}”" in texts[1]
    target = moved["instance"]["goal"]["target_block"]
    assert "ΔSB1" in texts[2] and f"`{target}`" in texts[2]


def test_a_discarded_episode_leaves_no_file_and_the_next_one_records(tmp_path):
    episodes, (first, second) = Episodes(), contexts(perturbations=("LB1",))
    recorder = RerunEpisodeRecorder(tmp_path, task=episodes.task)
    observation = episodes.stage(first)
    recorder.start(first, FEATURES, POSE_KEYS)
    recorder.step(0.0, observation, {"delta_x": 0.0, "delta_y": 0.0})
    recorder.discard()
    _, files = episodes.run(recorder, second, steps=3)
    recorder.close()
    assert sorted(p.name for p in (tmp_path / "rerun").iterdir()) == ["episode_000001.rrd", LAYOUT_FILE]
    assert files.rerun_path == "rerun/episode_000001.rrd"


def test_an_episode_that_ends_before_its_first_step_still_shows_scene_and_outcome(tmp_path):
    (context,) = contexts(perturbations=())
    recorder = RerunEpisodeRecorder(tmp_path)
    recorder.start(context, FEATURES, POSE_KEYS)
    outcome = Outcome(success=True, steps=0, path_length=0.0, scene_after=context.instance.scene, duration_s=0.0)
    files = recorder.end(scored(context, outcome, 0.0, 0.0))
    recorder.close()
    _, chunks = read_rrd(tmp_path / files.rerun_path)
    assert "success ✓" in static_row(chunks["/outcome"])["text"] and "/camera/top" not in chunks
    assert rerun_cli("rrd", "verify", str(tmp_path / files.rerun_path)).returncode == 0


def test_step_outside_an_episode_is_a_programming_error(tmp_path):
    recorder = RerunEpisodeRecorder(tmp_path)
    with pytest.raises(RuntimeError, match="call start"):
        recorder.step(0.0, {}, {})
    recorder.close()


def test_an_episode_the_disk_has_no_room_for_is_a_full_disk_before_rerun_writes(tmp_path, monkeypatch):
    episodes, (context,) = Episodes(), contexts(perturbations=())
    recorder = RerunEpisodeRecorder(tmp_path, task=episodes.task)
    monkeypatch.setattr(shutil, "disk_usage", lambda path: SimpleNamespace(total=1 << 30, used=1 << 30, free=4096))
    with pytest.raises(OSError, match="No space left on device"):
        episodes.run(recorder, context)
    recorder.close()
    assert list((tmp_path / "rerun").iterdir()) == []


def test_a_failed_rerun_write_is_one_line_and_leaves_no_partial_file(tmp_path, monkeypatch):
    episodes, (context,) = Episodes(), contexts(perturbations=())
    recorder = RerunEpisodeRecorder(tmp_path, task=episodes.task)

    def writer_stopped(self, **kwargs):
        raise RuntimeError("File-writer thread shut down prematurely")

    monkeypatch.setattr(rr.RecordingStream, "flush", writer_stopped)
    with pytest.raises(RerunWriteError, match=r"episode_000000.rrd.partial: Rerun could not write the episode \(File-"):
        episodes.run(recorder, context)
    recorder.close()
    assert list((tmp_path / "rerun").iterdir()) == []


def test_rollback_keeps_the_episodes_the_journal_names_and_removes_the_rest(tmp_path):
    rerun = tmp_path / "rerun"
    rerun.mkdir()
    for name in ("episode_000000.rrd", "episode_000002.rrd", "episode_000003.rrd.partial", LAYOUT_FILE):
        (rerun / name).write_bytes(b"x")
    episodes, (context,) = Episodes(), contexts(perturbations=())
    recorder = RerunEpisodeRecorder(tmp_path, task=episodes.task)
    record, files = episodes.run(recorder, context)
    recorder.rollback([dataclasses.replace(record, rerun_path=files.rerun_path)])
    recorder.close()
    assert sorted(p.name for p in rerun.iterdir()) == ["episode_000000.rrd", LAYOUT_FILE]


def threads() -> int:
    return len(os.listdir("/proc/self/task"))


@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="threads are counted from /proc")
def test_an_episode_leaves_no_rerun_stream_or_thread_behind(tmp_path):
    episodes, trials = Episodes(), contexts(perturbations=("LB1", "SB1"), n_bases=2)
    recorder = RerunEpisodeRecorder(tmp_path, task=episodes.task)
    episodes.run(recorder, trials[0], steps=3)
    before = threads()
    for trial in trials[1:]:
        episodes.run(recorder, trial, steps=3)
    assert threads() <= before
    recorder.close()
    reader, _ = read_rrd(tmp_path / "rerun" / f"episode_{trials[-1].index:06d}.rrd")
    assert len(reader.recordings()) == 1 and len(reader.blueprints()) == 1
