"""`python -m lerobot_contrast.review`: selecting episodes, the merged side-by-side recording, and opening it
in the native viewer or serving the web viewer on localhost."""

import contextlib
import os
import signal
import socket
import subprocess
import sys
import time
import urllib.request

import pytest

from lerobot_contrast import review
from lerobot_contrast.contrast.trial import TrialRecord
from lerobot_contrast.ports import free_port
from tests.record.conftest import STEPS, read_rrd, rerun_cli, static_row


def records(run_dir) -> list[TrialRecord]:
    return review.load_records(run_dir)


def test_filters_select_by_perturbation_outcome_and_base_and_group_by_base(recorded_run):
    all_records = records(recorded_run)
    bases = list(dict.fromkeys(r.base_id for r in all_records))
    chosen = review.select(all_records, perturbation="original,ΔLB1")
    assert [(r.base_id, r.perturbation) for r in chosen] == [(b, p) for b in bases for p in (None, "LB1")]
    assert review.select(all_records, base=bases[1]) == [r for r in all_records if r.base_id == bases[1]]
    failures = review.select(all_records, outcome="failure")
    assert failures == [r for r in all_records if not r.success] and 0 < len(failures) < len(all_records)
    with pytest.raises(review.ReviewError, match="--perturbation: no recorded episode has LB2; this run has LB1, SB1"):
        review.select(all_records, perturbation="original,LB2")
    present = {(r.base_id, bool(r.success)) for r in all_records}
    base, success = next((b, s) for b in bases for s in (True, False) if (b, s) not in present)
    with pytest.raises(review.ReviewError, match="no recorded episode matches the filters"):
        review.select(all_records, base=base, outcome="success" if success else "failure")


def test_the_merged_recording_puts_each_episode_in_its_own_subtree(recorded_run, tmp_path):
    chosen = review.select(records(recorded_run), base=records(recorded_run)[0].base_id)
    merged, missing = review.merge_episodes(recorded_run, chosen, tmp_path / "review.rrd")
    assert missing == [] and rerun_cli("rrd", "verify", str(merged)).returncode == 0
    reader, chunks = read_rrd(merged)
    assert len(reader.recordings()) == 1 and len(reader.blueprints()) == 1
    prefixes = [review.entity_prefix(r) for r in chosen]
    assert prefixes == [f"/episodes/trial_{r.index:06d}_{r.perturbation or 'original'}" for r in chosen]
    assert {path.split("/")[2] for path in chunks if path.startswith("/episodes/")} == {
        p.split("/")[2] for p in prefixes
    }
    for record, prefix in zip(chosen, prefixes, strict=True):
        frames = [c for c in chunks[f"{prefix}/camera/top"] if not c.is_static]
        assert sum(c.num_rows for c in frames) == STEPS
        assert all(set(c.timeline_names) == {"frame", "time"} for c in frames)
        assert static_row(chunks[f"{prefix}/properties/eval"])["trial_index"] == record.index
    assert static_row(chunks["/__properties/review"])["trials"] == [r.index for r in chosen]


def test_a_missing_episode_file_is_reported_and_left_out(recorded_run, tmp_path, capsys):
    run = tmp_path / "run"
    run.mkdir()
    (run / "journal.jsonl").write_text((recorded_run / "journal.jsonl").read_text())
    first, second = records(recorded_run)[:2]
    (run / "rerun").mkdir()
    (run / second.rerun_path).write_bytes((recorded_run / second.rerun_path).read_bytes())
    assert review.main([str(run), "--perturbation=original,LB1", f"--base={first.base_id}", "--save_only"]) == 0
    out, err = capsys.readouterr()
    assert f"1 episode file(s) missing, left out: {first.rerun_path}" in err
    assert "1 episode of 1 base instance:" in out and (run / "review" / "review.rrd").is_file()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--outcome=maybe"], "error: --outcome must be one of success, failure, got 'maybe'\n"),
        (["--perturbation=original,XX"], "error: --perturbation: no recorded episode has XX; this run has LB1, SB1"),
        (["--base=lt-0999"], "error: --base: no recorded episode has lt-0999; this run has lt-"),
        (["--colour=red"], "error: unknown flag --colour; see --help for the flags this command takes\n"),
    ],
)
def test_bad_flags_give_a_one_line_error(recorded_run, capsys, args, message):
    assert review.main([str(recorded_run), *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith(message) and err.count("\n") == 1


def test_a_directory_without_a_journal_is_refused(tmp_path, capsys):
    assert review.main([str(tmp_path), "--save_only"]) == 2
    assert "no journal.jsonl; pass a run directory written by lerobot_contrast.eval" in capsys.readouterr().err


def test_without_a_display_it_asks_for_the_web_viewer(recorded_run, monkeypatch, capsys):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(sys, "platform", "linux")
    assert review.main([str(recorded_run)]) == 2
    assert "no display to open the Rerun viewer on; pass --web" in capsys.readouterr().err


def test_with_a_display_it_opens_the_merged_file_in_the_native_viewer(recorded_run, monkeypatch, tmp_path):
    launched = []
    monkeypatch.setenv("DISPLAY", ":0")
    monkeypatch.setattr(review.subprocess, "run", lambda command, check: launched.append(command) or _Done())
    output = tmp_path / "merged.rrd"
    assert review.main([str(recorded_run), "--outcome=success", f"--output={output}"]) == 0
    assert launched == [[review.rerun_binary(), str(output)]]
    monkeypatch.undo()  # `review.subprocess` is the subprocess module itself
    assert rerun_cli("rrd", "verify", str(output)).returncode == 0


class _Done:
    returncode = 0


@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM])
def test_web_serves_the_viewer_on_localhost_until_ctrl_c_or_sigterm(recorded_run, tmp_path, stop):
    web, grpc = free_port(), free_port()
    command = [sys.executable, "-m", "lerobot_contrast.review", str(recorded_run), "--perturbation=SB1", "--web"]
    command += [f"--web_port={web}", f"--grpc_port={grpc}", f"--output={tmp_path / 'merged.rrd'}"]
    # A session of its own, so a failed test can stop the viewer the command started as well.
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        page = _get(f"http://127.0.0.1:{web}/", deadline=time.monotonic() + 60)
        assert "<html" in page and "Rerun" in page
        with socket.create_connection(("127.0.0.1", grpc), timeout=5):
            pass  # the recording is served over gRPC on the port the page points at
        proc.send_signal(stop)
        out, _ = proc.communicate(timeout=30)
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 0
    assert f"open http://127.0.0.1:{web}/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A{grpc}%2Fproxy in a browser" in out
    for port in (web, grpc):  # the viewer the command started is gone with it, and so are its ports
        with pytest.raises(OSError):
            socket.create_connection(("127.0.0.1", port), timeout=2).close()


def _get(url: str, deadline: float) -> str:
    while True:
        try:
            with urllib.request.urlopen(url, timeout=5) as response:
                return response.read().decode()
        except OSError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.3)


def test_a_run_still_writing_its_journal_is_read_without_touching_it(recorded_run, tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    torn = (recorded_run / "journal.jsonl").read_bytes() + b'{"version":1,"index":6,"base'
    (run / "journal.jsonl").write_bytes(torn)
    assert len(review.load_records(run)) == len(records(recorded_run))
    assert (run / "journal.jsonl").read_bytes() == torn
