"""What the page shows, without a browser: report's own numbers, the pairs and what changed in them, the videos'
episodes, and a run without a dataset or journal."""

import json

import pytest

from lerobot_contrast.record.journal import read_journal
from lerobot_contrast.view import trials
from lerobot_contrast.view.episodes import Dataset
from lerobot_contrast.view.payload import build, load_inputs
from tests.view.conftest import report_rows

pytestmark = pytest.mark.xdist_group("view")


def table(doc, title):
    return next(t for t in doc["report"]["tables"] if t["title"].startswith(title))


def test_the_tables_hold_report_md_s_own_strings(runs):
    doc = build(load_inputs([str(runs["noisy"])]), live=False)
    shown = table(doc, "SPL per perturbation")["rows"]
    per_perturbation = report_rows(runs["report"], "SPL per perturbation")
    changes = dict(report_rows(runs["report"], "Sensitivity"))
    assert [row[:2] for row in shown] == per_perturbation
    assert all(row[2] == changes.get(row[0], "-") for row in shown)
    assert table(doc, "Summary")["rows"] == report_rows(runs["report"], "Summary")
    assert table(doc, "SPL per task family")["rows"] == report_rows(runs["report"], "SPL per task family")


def test_every_perturbed_trial_that_ran_is_paired_with_its_base_s_original(runs):
    records = read_journal(runs["noisy"] / "journal.jsonl")
    by_index = {r.index: r for r in records}
    pairs = trials.pairs(records)
    ran = [r for r in records if r.perturbation is not None and r.instance is not None]
    assert sorted(p["perturbed"] for p in pairs) == [r.index for r in ran] and ran
    for pair in pairs:
        original, perturbed = by_index[pair["original"]], by_index[pair["perturbed"]]
        assert original.perturbation is None and original.base_id == perturbed.base_id
        both = original.status == perturbed.status == "done"
        assert pair["flip"] == (both and original.success != perturbed.success)
        assert " ".join(text for text, _ in pair["words"][1]) == perturbed.instance.instruction
        if perturbed.axis in ("L", "LB"):  # a new wording moves no object
            assert pair["moved"] == []
    assert any(p["flip"] for p in pairs)  # the noisy oracle flips some: the page has flips to show


def test_changed_words_and_moved_objects_are_marked():
    left, right = trials.word_marks("push the red star to the left", "push the blue star to the right")
    assert left == [["push the", False], ["red", True], ["star to the", False], ["left", True]]
    assert right == [["push the", False], ["blue", True], ["star to the", False], ["right", True]]
    from lerobot_contrast.contrast.scene import Pose, Scene

    before = Scene(objects={"a": Pose(0.1, 0.0), "b": Pose(0.3, 0.1), "c": Pose(0.2, 0.2)})
    after = Scene(objects={"a": Pose(0.1, 0.0), "b": Pose(0.3, 0.2), "d": Pose(0.4, 0.0)})
    moved = {m["name"]: m for m in trials.moved_objects(before, after)}
    assert set(moved) == {"b", "c", "d"} and moved["b"]["distance"] == pytest.approx(0.1)
    assert moved["c"]["to"] is None and moved["d"]["from"] is None


def test_each_recorded_trial_has_its_episode_videos_and_signals(runs):
    dataset = Dataset(runs["noisy"])
    assert dataset.absent_why({"record_dataset": True}) is None
    recorded = [r for r in read_journal(runs["noisy"] / "journal.jsonl") if r.dataset_episode is not None]
    for record in recorded:
        episode = dataset.episode(record.dataset_episode)
        video = episode["videos"][0]
        assert (dataset.root / video["path"]).is_file() and video["span"][1] > video["span"][0]
        signals = {s["name"]: s for s in episode["signals"]}
        assert {"observation.state", "action"} <= set(signals)
        assert len(signals["action"]["time"]) == record.steps == len(signals["action"]["series"][0])


def test_a_run_without_a_dataset_says_its_videos_are_absent_and_shows_the_rest(runs):
    doc = build(load_inputs([str(runs["oracle"])]), live=False)
    (run,) = doc["runs"]
    assert "recorded no dataset" in run["videos_absent"] and run["pairs"] and run["curves"]["cost"]
    json.dumps(doc)  # a document the page can take


def test_a_run_whose_dataset_was_left_behind_says_so(runs, copy_of):
    import shutil

    run = copy_of(runs["noisy"])
    shutil.rmtree(run / "dataset")
    (only,) = build(load_inputs([str(run)]), live=False)["runs"]
    assert "recorded a dataset, but" in only["videos_absent"] and only["pairs"]


def test_two_runs_of_one_plan_are_shown_policy_beside_policy(runs):
    doc = build(load_inputs([str(runs["noisy"]), str(runs["oracle"])]), live=False)
    assert doc["same_plan"] == [["r0", "r1"]]
    assert table(doc, "Policies on the same plan")["rows"][0][:2] == ["noisy", "oracle"]


def test_the_running_estimate_is_report_s(runs):
    from lerobot_contrast.reporting import load_run, stats

    run = load_run(str(runs["noisy"]))
    curve = trials.curves(run, "spl")
    done = stats.done(run.results).sort_values("index")
    assert curve["trials"][-1] == len(done)
    assert curve["estimate"][-1] == pytest.approx(stats.full_value(run.results, "spl"), abs=1e-4)


def test_the_viewer_reads_the_dataset_where_the_recorder_writes_it():
    from lerobot_contrast.record import dataset
    from lerobot_contrast.view import episodes

    assert episodes.DATASET_DIR == dataset.DATASET_DIR


def test_an_ab_session_shows_report_s_interleaved_comparison_and_the_verdict(runs):
    doc = build(load_inputs([str(runs["session"])]), live=False)
    (session,) = doc["sessions"]
    assert [p["run"] for p in session["policies"]] == ["r0", "r1"] and doc["same_plan"] == [["r0", "r1"]]
    assert session["stopping"]["pairs"][0]["verdict"] in ("first better", "second better", "undecided")
    tables = {t["title"]: t["rows"] for t in doc["report"]["tables"]}
    report = runs["session_report"]
    assert tables["session: the sequential paired test"] == report_rows(report, "Interleaved comparison: session")
    assert tables["session: Each policy"] == report_rows(report, "Each policy")
    minus = next(title for title in tables if " minus " in title)
    assert tables[minus] == report_rows(report, minus.split(": ", 1)[1])


def test_an_audited_trial_carries_the_persons_label_for_the_page_to_mark():
    from lerobot_contrast.contrast.trial import TrialRecord
    from lerobot_contrast.view.trials import trial_json

    def record(extra):
        return TrialRecord(0, "b0", None, None, "f", "reset", 0, "done", None, 0.0, 0.0, success=True, extra=extra)

    assert (trial_json(record({"audit": False}))["audit"], trial_json(record({}))["audit"]) == (False, None)
    assert trial_json(record({"label_asked": True}))["label_asked"] and not trial_json(record({}))["label_asked"]
