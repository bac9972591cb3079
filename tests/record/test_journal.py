import errno
import json
import os
import signal

import pytest

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.trial import TrialRecord
from lerobot_contrast.record.journal import Journal, JournalError, read_journal
from lerobot_contrast.record.run_dir import RunDirError, open_run_dir


def record(index, perturbation=None):
    scene = Scene({"red_moon": Pose(0.3, 0.1, 0.5)}, robot=Pose(0.3, 0.0))
    instance = Instance(f"lt-{index}", "block2block", "push the red moon", scene, {"block": "red_moon"})
    return TrialRecord(
        index=index,
        base_id=instance.id,
        perturbation=perturbation,
        axis=None,
        family="block2block",
        staging="reset",
        repeat=0,
        status="done",
        instance=instance,
        cost=0.25,
        cumulative_cost=0.25 * (index + 1),
        success=True,
        spl=0.9,
        steps=12,
        scene_after=scene,
    )


def test_records_round_trip_through_the_journal(tmp_path):
    journal = Journal.open(tmp_path / "journal.jsonl")
    journal.append(record(0))
    journal.append(record(1, "LB1"))
    again = Journal.open(tmp_path / "journal.jsonl")
    assert again.records == [record(0), record(1, "LB1")]
    first = json.loads((tmp_path / "journal.jsonl").read_text().splitlines()[0])
    assert first["version"] == 1 and first["instance"]["scene"]["objects"]["red_moon"] == [0.3, 0.1, 0.5]


def test_ctrl_c_during_an_append_lands_after_the_record_is_in_file_and_memory(tmp_path, monkeypatch):
    journal = Journal.open(tmp_path / "journal.jsonl")
    real_fsync = os.fsync

    def fsync_then_ctrl_c(fd):
        real_fsync(fd)
        os.kill(os.getpid(), signal.SIGINT)

    monkeypatch.setattr(os, "fsync", fsync_then_ctrl_c)
    with pytest.raises(KeyboardInterrupt):
        journal.append(record(0))
    assert journal.records == [record(0)]
    assert Journal.open(tmp_path / "journal.jsonl").records == [record(0)]


def test_a_torn_last_line_from_a_killed_run_is_dropped_and_the_file_repaired(tmp_path):
    path = tmp_path / "journal.jsonl"
    journal = Journal.open(path)
    journal.append(record(0))
    complete = path.read_bytes()
    path.write_bytes(complete + json.dumps({"version": 1, **record(1).to_json()}).encode()[:57])
    again = Journal.open(path)
    assert again.records == [record(0)] and again.torn_bytes == 57
    assert path.read_bytes() == complete
    again.append(record(1))
    assert Journal.open(path).records == [record(0), record(1)]


def test_reading_a_journal_being_written_leaves_it_untouched(tmp_path):
    path = tmp_path / "journal.jsonl"
    Journal.open(path).append(record(0))
    writing = path.read_bytes() + json.dumps({"version": 1, **record(1).to_json()}).encode()[:57]
    path.write_bytes(writing)
    assert read_journal(str(path)) == [record(0)]
    assert path.read_bytes() == writing
    with pytest.raises(JournalError, match="no such journal"):
        read_journal(tmp_path / "missing.jsonl")


def test_damage_before_the_last_line_is_an_error_not_silently_dropped(tmp_path):
    path = tmp_path / "journal.jsonl"
    path.write_text("{not json\n" + json.dumps({"version": 1, **record(0).to_json()}) + "\n")
    with pytest.raises(JournalError, match="line 1 is not valid JSON"):
        Journal.open(path)


def test_a_journal_from_another_format_version_is_refused(tmp_path):
    path = tmp_path / "journal.jsonl"
    path.write_text(json.dumps({"version": 99, **record(0).to_json()}) + "\n")
    with pytest.raises(JournalError, match="journal version 99"):
        Journal.open(path)


def test_records_must_arrive_in_plan_order(tmp_path):
    journal = Journal.open(tmp_path / "journal.jsonl")
    with pytest.raises(JournalError, match="expected trial 0, got 3"):
        journal.append(record(3))


def test_an_existing_run_is_not_overwritten_without_resume(tmp_path):
    run = tmp_path / "run"
    open_run_dir(run, {"seed": 0}, resume=False).close()
    with pytest.raises(RunDirError, match="already exists; pass --resume=true"):
        open_run_dir(run, {"seed": 0}, resume=False)
    with open_run_dir(run, {"seed": 0, "resume": True}, resume=True) as resumed:
        assert resumed.path == run


def test_resume_refuses_changed_settings_and_missing_runs(tmp_path):
    run = tmp_path / "run"
    open_run_dir(run, {"seed": 0, "budget": 5.0}, resume=False).close()
    with pytest.raises(RunDirError, match=r"other settings, --budget=9.0 \(was 5.0\); drop those flags"):
        open_run_dir(run, {"seed": 0, "budget": 9.0}, resume=True)
    with pytest.raises(RunDirError, match="holds no run to resume"):
        open_run_dir(tmp_path / "nothing", {"seed": 0}, resume=True)


def test_resume_on_a_twin_started_again_at_other_ports(tmp_path):
    """A twin (or any server) started again answers at new ports: its addresses are not settings, what they serve is."""
    run = tmp_path / "run"
    then = {"clock": "tcp://127.0.0.1:5557", "policy": {"options": {"placement": "tcp://127.0.0.1:58159"}}}
    open_run_dir(run, then, resume=False).close()
    now = {"clock": "tcp://127.0.0.1:6001", "policy": {"options": {"placement": "tcp://127.0.0.1:58021"}}}
    open_run_dir(run, now, resume=True).close()
    with pytest.raises(RunDirError, match=r"other settings, --clock=\"wall\""):
        open_run_dir(run, {**now, "clock": "wall"}, resume=True)


def test_an_unwritable_output_dir_names_the_flag(tmp_path):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    with pytest.raises(RunDirError, match=r"--output_dir: cannot write to .*a_file/run \(Not a directory\)"):
        open_run_dir(blocker / "run", {"seed": 0}, resume=False)


def line(trial, **changes):
    return json.dumps({"version": 1, **record(trial).to_json(), **changes})


MALFORMED = {
    "a duplicated line": ([line(0), line(1), line(1), line(2)], "line 3 holds trial 1, expected trial 2"),
    "a deleted middle line": ([line(0), line(2)], "line 2 holds trial 2, expected trial 1"),
    "an empty line": ([line(0), "", line(1)], "line 2 is not valid JSON"),
    "a line that is not an object": ([line(0), "[1, 2]"], "line 2 is not a trial record"),
    "a string index": ([line(0), line(1, index="1")], r"line 2 is not a valid trial record \(field index\)"),
    "a missing field": ([line(0, base_id=None)], r"line 1 is not a valid trial record \(field base_id\)"),
    "an unknown status": ([line(0, status="won")], r"\(field status\)"),
    "a broken instance": ([line(0, instance={"id": "x"})], r"\(instance or scene_after\)"),
    "a negative index": ([line(0, index=-1)], r"\(field index\)"),
}


@pytest.mark.parametrize("case", MALFORMED)
def test_a_malformed_journal_is_refused_naming_the_line_and_left_as_it_was(tmp_path, case):
    lines, message = MALFORMED[case]
    path = tmp_path / "journal.jsonl"
    path.write_text("".join(text + "\n" for text in lines))
    before = path.read_bytes()
    with pytest.raises(JournalError, match=message) as refused:
        Journal.open(path)
    assert "\n" not in str(refused.value) and "restore journal.jsonl from a backup" in str(refused.value)
    assert path.read_bytes() == before


def test_a_journal_that_is_a_directory_is_one_line(tmp_path):
    (tmp_path / "journal.jsonl").mkdir()
    with pytest.raises(JournalError, match=r"cannot read the journal \(Is a directory\)"):
        Journal.open(tmp_path / "journal.jsonl")


def test_a_full_disk_during_an_append_leaves_no_partial_line(tmp_path, monkeypatch):
    path = tmp_path / "journal.jsonl"
    journal = Journal.open(path)
    journal.append(record(0))
    before = path.read_bytes()
    real_write = os.write

    def half_then_full(fd, data):
        if len(data) > 20:
            return real_write(fd, data[:20])
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "write", half_then_full)
    with pytest.raises(OSError, match="No space left"):
        journal.append(record(1))
    monkeypatch.undo()
    assert path.read_bytes() == before and journal.records == [record(0)]
    journal.append(record(1))
    assert Journal.open(path).records == [record(0), record(1)]
