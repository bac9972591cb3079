"""The run directory's lock and setup: one writer at a time, released when its process dies however it dies, and a
run directory that could not be set up leaves nothing behind."""

import errno
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from lerobot_contrast.record.run_dir import DiskFullError, RunDirError, open_run_dir, write_json_atomic
from lerobot_contrast.record.run_lock import RunLockedError

HOLDER = """
import sys, time
from pathlib import Path
from lerobot_contrast.record.run_dir import open_run_dir
run_dir = open_run_dir(Path(sys.argv[1]), {"seed": 0}, resume=False)
print("locked", flush=True)
time.sleep(300)
"""


def test_a_second_writer_is_refused_until_the_first_closes(tmp_path):
    run = tmp_path / "run"
    first = open_run_dir(run, {"seed": 0}, resume=False)
    with pytest.raises(RunLockedError, match=rf"run is in use by process {os.getpid()} \(an evaluation, since "):
        open_run_dir(run, {"seed": 0}, resume=True)
    first.close()
    with open_run_dir(run, {"seed": 0}, resume=True) as second:
        assert second.journal.records == []


def test_the_lock_dies_with_a_killed_holder(tmp_path):
    run = tmp_path / "run"
    holder = subprocess.Popen([sys.executable, "-c", HOLDER, str(run)], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline() == "locked\n"
        with pytest.raises(RunLockedError, match=rf"in use by process {holder.pid} "):
            open_run_dir(run, {"seed": 0}, resume=True)
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait()
    with open_run_dir(run, {"seed": 0}, resume=True) as resumed:
        assert resumed.path == run


def full(*args, **kwargs):
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def test_a_new_run_on_a_full_disk_leaves_nothing_behind(tmp_path, monkeypatch):
    monkeypatch.setattr(Path, "write_text", full)
    run = tmp_path / "new" / "run"
    with pytest.raises(DiskFullError, match=r"no space left on the disk holding .*/run; free space and run again"):
        open_run_dir(run, {"seed": 0}, resume=False)
    assert not run.exists()


def test_an_atomic_write_that_fails_leaves_no_temporary_file(tmp_path, monkeypatch):
    monkeypatch.setattr(os, "replace", full)
    with pytest.raises(OSError):
        write_json_atomic(tmp_path / "plan.json", {"version": 1})
    assert list(tmp_path.iterdir()) == []


def test_an_output_dir_that_is_a_file_is_one_line(tmp_path):
    blocker = tmp_path / "run"
    blocker.write_text("")
    with pytest.raises(RunDirError, match="--output_dir: .*run is a file; choose a directory"):
        open_run_dir(blocker, {"seed": 0}, resume=False)
