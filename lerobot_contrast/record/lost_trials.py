"""Trials a lost robot aborted at the end of a journal: cut off on resume so that they run again."""

from __future__ import annotations

import os
from collections.abc import Callable

from lerobot_contrast.record.journal import Journal


def lost_at_end(journal: Journal) -> int:
    """How many of the journal's last trials ended because the robot disconnected. Trials the session went on
    after are not counted: the trials after them started from the scene they left."""
    count = 0
    for record in reversed(journal.records):
        if record.status != "aborted" or record.extra.get("ended_by") != "disconnected":
            break
        count += 1
    return count


def drop_lost_trials(journal: Journal, say: Callable[[str], None] | None = None) -> None:
    """Cut the last trials a lost robot aborted off the journal (file and records), so a resumed run runs them
    again; the observers' rollback to the journal then removes their episodes."""
    lost = lost_at_end(journal)
    if not lost:
        return
    keep = len(journal.records) - lost
    raw = journal.path.read_bytes()
    end = 0
    for _ in range(keep):  # the journal holds one line per trial
        end = raw.index(b"\n", end) + 1
    with journal.path.open("r+b") as handle:
        handle.truncate(end)
        os.fsync(handle.fileno())
    if say is not None:
        trials = ", ".join(str(r.index) for r in journal.records[keep:])
        say(f"trial {trials} was aborted when the robot disconnected; it runs again (--rerun_aborted=false keeps it)")
    del journal.records[keep:]
