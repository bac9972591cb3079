"""The append-only trial journal (`journal.jsonl`): one JSON line per trial, flushed and fsynced per trial.

This module owns the journal format and its checks. Line N holds trial N-1, and every line must be a complete
record: a run killed mid-write leaves at most a torn last line, which `Journal.open` drops (and says so), so a
resumed run re-executes exactly the trials that were not recorded. Anything else is refused, naming the line.
"""

from __future__ import annotations

import json
import os
import signal
import threading
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, get_args

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.trial import Status, TrialRecord

JOURNAL_VERSION = 1
# Each field's JSON types (a trailing "?": it may be null); the fields a record needs are those without a default.
FIELD_TYPES = {
    "index": "int", "base_id": "str", "perturbation": "str?", "axis": "str?", "family": "str", "staging": "str",
    "repeat": "int", "status": "str", "instance": "dict?", "cost": "number", "cumulative_cost": "number",
    "success": "bool?", "spl": "number?", "progress": "number?", "path_length": "number?",
    "reference_length": "number?", "steps": "int?", "duration_s": "number?", "started_at": "str?",
    "scene_after": "dict?", "rerun_path": "str?", "dataset_episode": "int?", "extra": "dict",
}  # fmt: skip
REQUIRED = (
    "index", "base_id", "perturbation", "axis", "family", "staging", "repeat", "status", "instance", "cost",
    "cumulative_cost",
)  # fmt: skip
# The fields that say which trial a line is: a resumed run's plan must give the same, line by line.
PLANNED_FIELDS = ("index", "base_id", "perturbation", "family", "staging", "repeat", "instance")
DAMAGED = "restore journal.jsonl from a backup, or run the evaluation again into a new --output_dir"
ANOTHER_RUN = (
    "it comes from another run, or config.json or the journal was edited; restore the run's own config.json and "
    "journal.jsonl, or run the evaluation again into a new --output_dir"
)


class JournalError(UserError):
    pass


class Journal:
    def __init__(self, path: Path, records: list[TrialRecord], torn_bytes: int = 0) -> None:
        self.path = path
        self.records = records
        self.torn_bytes = torn_bytes  # what `open` cut off: a last line torn by a kill (0: none)

    @classmethod
    def open(cls, path: Path) -> Journal:
        """Open the journal at `path` for appending (creating it if missing), dropping a torn final line."""
        if not path.exists():
            path.touch()
            return cls(path, [])
        raw = _read(path)
        records, good_end = _parse(path, raw)
        if good_end != len(raw):
            with path.open("r+b") as handle:
                handle.truncate(good_end)
        return cls(path, records, len(raw) - good_end)

    def append(self, record: TrialRecord) -> None:
        if record.index != len(self.records):
            raise JournalError(f"{self.path}: expected trial {len(self.records)}, got {record.index}")
        line = json.dumps({"version": JOURNAL_VERSION, **record.to_json()}, separators=(",", ":"))
        with _interrupts_deferred():
            _append_line(self.path, (line + "\n").encode("utf-8"))
            self.records.append(record)

    def truncate(self, keep: int) -> None:
        """Keep only the first `keep` trials, in the file (one line each) and in `records`."""
        raw = self.path.read_bytes()
        end = 0
        for _ in range(keep):
            end = raw.index(b"\n", end) + 1
        with _interrupts_deferred(), self.path.open("r+b") as handle:
            handle.truncate(end)
            os.fsync(handle.fileno())
            del self.records[keep:]

    def check_planned(self, expected: Sequence[TrialRecord], planned: int) -> None:
        """Refuse a journal whose lines are not the trials `expected`: the run's plan, replayed with the outcomes
        the journal recorded (`planned` trials in all; fewer are expected where the budget ran out)."""
        for number, (have, want) in enumerate(zip(self.records, expected, strict=False), start=1):
            differ = [name for name in PLANNED_FIELDS if getattr(have, name) != getattr(want, name)]
            if differ:
                raise JournalError(
                    f"{self.path}: line {number} is not trial {want.index} of this run's plan ({', '.join(differ)} "
                    f"differ): {ANOTHER_RUN}"
                )
        if len(self.records) > len(expected):
            beyond = "plan's" if len(expected) == planned else "budget's"
            raise JournalError(
                f"{self.path}: {len(self.records)} lines, beyond the {beyond} {len(expected)} trials from line "
                f"{len(expected) + 1}: {ANOTHER_RUN}"
            )


def _append_line(path: Path, data: bytes) -> None:
    fd = os.open(path, os.O_WRONLY | os.O_APPEND)
    try:
        start = os.lseek(fd, 0, os.SEEK_END)
        try:
            while data:
                data = data[os.write(fd, data) :]
            os.fsync(fd)
        except OSError:  # a full disk: leave no partial line behind
            os.ftruncate(fd, start)
            raise
    finally:
        os.close(fd)


def read_journal(path: str | Path) -> list[TrialRecord]:
    """The records of the journal at `path`, read without touching it: its run may still be writing it."""
    path = Path(path)
    if not path.is_file():
        raise JournalError(f"{path}: no such journal; pass the journal.jsonl of a run directory")
    return _parse(path, _read(path))[0]


def _read(path: Path) -> bytes:
    try:
        return path.read_bytes()
    except OSError as error:
        raise JournalError(f"{path}: cannot read the journal ({error.strerror}); {DAMAGED}") from None


def _parse(path: Path, raw: bytes) -> tuple[list[TrialRecord], int]:
    """The complete records in `raw`, and the byte offset where they end (a line being written, or torn by a
    kill, has no newline yet and is left out)."""
    records: list[TrialRecord] = []
    good_end = 0
    lines = raw.split(b"\n")
    for number, line in enumerate(lines[:-1], start=1):  # after the last newline: an incomplete line
        try:
            data = json.loads(line)
        except (json.JSONDecodeError, UnicodeDecodeError):
            raise JournalError(f"{path}: line {number} is not valid JSON; {DAMAGED}") from None
        record = _decode(path, number, data)
        if record.index != number - 1:
            raise JournalError(
                f"{path}: line {number} holds trial {record.index}, expected trial {number - 1} "
                f"(a line was duplicated, deleted or moved); {DAMAGED}"
            )
        records.append(record)
        good_end += len(line) + 1
    return records, good_end


def _decode(path: Path, number: int, data: Any) -> TrialRecord:
    where = f"{path}: line {number}"
    if not isinstance(data, dict):
        raise JournalError(f"{where} is not a trial record (a JSON object); {DAMAGED}")
    version = data.pop("version", None)
    if version != JOURNAL_VERSION:
        raise JournalError(f"{where} has journal version {version!r}, this release reads {JOURNAL_VERSION}")
    wrong = [name for name in REQUIRED if name not in data]
    wrong += [name for name, kind in FIELD_TYPES.items() if name in data and not _is(data[name], kind)]
    if data.get("status") not in get_args(Status):
        wrong.append("status")
    if wrong:
        raise JournalError(f"{where} is not a valid trial record (field {', '.join(dict.fromkeys(wrong))}); {DAMAGED}")
    try:
        return TrialRecord.from_json(data)
    except (AttributeError, KeyError, TypeError, ValueError):
        raise JournalError(f"{where} is not a valid trial record (instance or scene_after); {DAMAGED}") from None


def _is(value: Any, kind: str) -> bool:
    if kind.endswith("?"):
        return value is None or _is(value, kind[:-1])
    if kind == "bool":
        return isinstance(value, bool)
    if isinstance(value, bool):  # JSON true is no number
        return False
    types = {"int": int, "number": (int, float), "str": str, "dict": dict}[kind]
    return isinstance(value, types) and (kind != "int" or value >= 0)


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
