"""A shorter soak (scripts/bench/soak.py): a recorded session's threads and open files do not grow with its episodes."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "bench" / "soak.py"


@pytest.mark.slow
def test_threads_and_open_files_do_not_grow_over_a_recorded_session(tmp_path):
    command = [sys.executable, str(SCRIPT), "--trials=40", "--every=10", f"--output_dir={tmp_path / 'run'}"]
    result = subprocess.run(command, capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]
    last = result.stdout.strip().splitlines()[-1]
    figures = dict(pair.split("=") for pair in last.split())
    assert list(figures) == [
        "trials", "threads_start", "threads_end", "fds_start", "fds_end", "rss_mb_start", "rss_mb_end",
        "s_per_trial_first100", "s_per_trial_last100",
    ]  # fmt: skip
    assert figures["trials"] == "40"
    assert int(figures["threads_end"]) <= int(figures["threads_start"]), last
    assert int(figures["fds_end"]) <= int(figures["fds_start"]), last
    journal = (tmp_path / "run" / "journal.jsonl").read_text().splitlines()
    assert len(journal) == 40 and len(list((tmp_path / "run" / "rerun").glob("episode_*.rrd"))) == 40
