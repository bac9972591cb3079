"""Trials a lost robot aborted at the end of a journal: cut off on resume so that they run again."""

from __future__ import annotations

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
    trials = ", ".join(str(r.index) for r in journal.records[keep:])
    journal.truncate(keep)
    if say is not None:
        say(f"trial {trials} was aborted when the robot disconnected; it runs again (--rerun_aborted=false keeps it)")
