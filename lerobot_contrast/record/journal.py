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
        """Open the journal at `path` for appending (creating it if missing), dropping a torn final line."""
        if not path.exists():
            path.touch()
            return cls(path, [])
        raw = path.read_bytes()
        records, good_end = _parse(path, raw)
        if good_end != len(raw):
            with path.open("r+b") as handle:
                handle.truncate(good_end)
        return cls(path, records)

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


def read_journal(path: str | Path) -> list[TrialRecord]:
    """The records of the journal at `path`, read without touching it: its run may still be writing it."""
    path = Path(path)
    if not path.is_file():
        raise JournalError(f"{path}: no such journal; pass the journal.jsonl of a run directory")
    return _parse(path, path.read_bytes())[0]


def _parse(path: Path, raw: bytes) -> tuple[list[TrialRecord], int]:
    """The complete records in `raw`, and the byte offset where they end (a line being written, or torn by a
    kill, has no newline yet and is left out)."""
    records: list[TrialRecord] = []
    good_end = 0
    lines = raw.split(b"\n")
    for number, line in enumerate(lines[:-1], start=1):  # after the last newline: an incomplete line
        if line.strip():
            try:
                data = json.loads(line)
            except json.JSONDecodeError:
                raise JournalError(f"{path}: line {number} is not valid JSON; the journal is damaged") from None
            records.append(_decode(path, number, data))
        good_end += len(line) + 1
    return records, good_end


def _decode(path: Path, number: int, data: dict) -> TrialRecord:
    version = data.pop("version", None)
    if version != JOURNAL_VERSION:
        raise JournalError(
            f"{path}: line {number} has journal version {version!r}, this release reads {JOURNAL_VERSION}"
        )
    return TrialRecord.from_json(data)


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
