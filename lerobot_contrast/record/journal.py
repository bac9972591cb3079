"""The append-only trial journal (`journal.jsonl`): one JSON line per trial, flushed and fsynced per trial.

This module owns the journal format. A run killed mid-write leaves at most a torn last line, which
`Journal.open` drops, so a resumed run re-executes exactly the trials that were not recorded.
"""

from __future__ import annotations

import json
import os
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.trial import TrialRecord

JOURNAL_VERSION = 1


class JournalError(UserError):
    pass


class Journal:
    def __init__(self, path: Path, records: list[TrialRecord]) -> None:
        self.path = path
        self.records = records

    @classmethod
    def open(cls, path: Path) -> Journal:
        """Read the journal at `path` (creating it if missing), repairing a torn final line."""
        if not path.exists():
            path.touch()
            return cls(path, [])
        raw = path.read_bytes()
        records: list[TrialRecord] = []
        good_end = 0
        lines = raw.split(b"\n")
        for number, line in enumerate(lines, start=1):
            is_last = number == len(lines)
            if not line.strip():
                good_end += len(line) + (0 if is_last else 1)
                continue
            try:
                data = json.loads(line)
            except json.JSONDecodeError:
                if is_last:  # torn write from a killed run: drop it
                    break
                raise JournalError(f"{path}: line {number} is not valid JSON; the journal is damaged") from None
            if is_last:  # a complete record always ends with a newline
                break
            records.append(cls._decode(path, number, data))
            good_end += len(line) + 1
        if good_end != len(raw):
            with path.open("r+b") as handle:
                handle.truncate(good_end)
        return cls(path, records)

    @staticmethod
    def _decode(path: Path, number: int, data: dict) -> TrialRecord:
        version = data.pop("version", None)
        if version != JOURNAL_VERSION:
            raise JournalError(
                f"{path}: line {number} has journal version {version!r}, this release reads {JOURNAL_VERSION}"
            )
        return TrialRecord.from_json(data)

    def append(self, record: TrialRecord) -> None:
        if record.index != len(self.records):
            raise JournalError(f"{self.path}: expected trial {len(self.records)}, got {record.index}")
        line = json.dumps({"version": JOURNAL_VERSION, **record.to_json()}, separators=(",", ":"))
        with _interrupts_deferred():
            with self.path.open("a", encoding="utf-8") as handle:
                handle.write(line + "\n")
                handle.flush()
                os.fsync(handle.fileno())
            self.records.append(record)


@contextmanager
def _interrupts_deferred() -> Iterator[None]:
    """Hold a Ctrl-C until the block ends, so a trial is either in the file and in memory, or in neither."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        if caught:
            os.kill(os.getpid(), signal.SIGINT)
