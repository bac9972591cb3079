"""The run directory: config.json, journal.jsonl, results.parquet and summary.json, created or resumed safely
by one writer at a time (see run_lock), and a full disk said in one line."""

from __future__ import annotations

import errno
import json
import os
import re
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.record.journal import Journal
from lerobot_contrast.record.run_lock import LOCK_FILE, RunLock

# Settings that may differ between the original run and its resumption.
RESUME_FREE_KEYS = ("resume", "dry_run", "output_dir", "operator", "push_to_hub", "repo_id", "private")


class RunDirError(UserError):
    pass


class DiskFullError(UserError):
    pass


@dataclass
class RunDir:
    path: Path
    journal: Journal
    lock: RunLock

    @property
    def config_path(self) -> Path:
        return self.path / "config.json"

    @property
    def results_path(self) -> Path:
        return self.path / "results.parquet"

    @property
    def summary_path(self) -> Path:
        return self.path / "summary.json"

    def write_summary(self, summary: dict[str, Any]) -> None:
        write_json_atomic(self.summary_path, summary)

    def close(self) -> None:
        """Let the next writer in."""
        self.lock.release()

    def __enter__(self) -> RunDir:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


def write_json_atomic(path: Path, data: Any) -> None:
    tmp = path.with_name(path.name + ".tmp")
    try:
        tmp.write_text(json.dumps(data, indent=2, sort_keys=False) + "\n", encoding="utf-8")
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def no_space(error: BaseException) -> bool:
    """Whether `error` is a full disk (pyarrow and PyAV say so in the message, not always in `errno`)."""
    return isinstance(error, OSError) and (error.errno == errno.ENOSPC or "No space left on device" in str(error))


@contextmanager
def disk_full_said(path: Path, then: str) -> Iterator[None]:
    """Turn a full disk while writing under `path` into one line saying what to do `then`."""
    try:
        yield
    except OSError as error:
        if not no_space(error):
            raise
        raise DiskFullError(f"no space left on the disk holding {path}; free space and {then}") from None


def comparable_settings(config: dict[str, Any]) -> dict[str, Any]:
    """The settings two sessions of one run must share: all but where it is written, who operates it, where it
    is published, the robot's address and any network address (a twin or a server started again answers at
    another port: `--clock=tcp://...`, a policy's `placement` option)."""
    comparable = {k: _without_addresses(v) for k, v in config.items() if k not in RESUME_FREE_KEYS}
    if isinstance(comparable.get("robot"), dict):  # the same robot may come back at a new address or port
        comparable["robot"] = {"type": comparable["robot"].get("type")}
    return comparable


def _without_addresses(value: Any) -> Any:
    """`value` with every network address (`scheme://host:port`) read as its scheme alone."""
    if isinstance(value, Mapping):
        return {key: _without_addresses(item) for key, item in value.items()}
    if isinstance(value, str) and re.fullmatch(r"[a-z]+://[^/\s]+:\d+", value):
        return value.split("://")[0] + "://"
    return value


def open_run_dir(
    path: Path,
    config: dict[str, Any],
    resume: bool,
    holder: str = "an evaluation",
    defaults: Mapping[str, Any] | None = None,
) -> RunDir:
    """Create a new run directory, or reopen one with `resume`, locked for `holder`; refuses anything ambiguous.
    On resume a setting the stored config.json lacks (one added to the tool since the run started) reads as its
    value in `defaults`."""
    if resume:
        return _resume(path, config, holder, defaults or {})
    return _create(path, config, holder)


def with_defaults(stored: Mapping[str, Any], defaults: Mapping[str, Any]) -> dict[str, Any]:
    """`stored`, with each key it lacks (at any depth) taken from `defaults`."""
    out = dict(defaults) | dict(stored)
    for key, value in stored.items():
        if isinstance(value, Mapping) and isinstance(defaults.get(key), Mapping):
            out[key] = with_defaults(value, defaults[key])
    return out


def _resume(path: Path, config: dict[str, Any], holder: str, defaults: Mapping[str, Any]) -> RunDir:
    config_path = path / "config.json"
    if not config_path.exists():
        raise RunDirError(f"--resume: {path} holds no run to resume (no config.json); drop --resume to start one")
    lock = RunLock.acquire(path, holder)
    try:
        now = comparable_settings(config)
        then = comparable_settings(with_defaults(_stored_config(config_path), defaults))
        changed = [
            f"--{k}={json.dumps(now[k])} (was {json.dumps(then.get(k))})" for k in sorted(now) if then.get(k) != now[k]
        ]
        if changed:
            raise RunDirError(
                f"--resume: {path} was started with other settings, {'; '.join(changed)}; drop those flags "
                "(a resumed run reads its settings from config.json) or choose a new --output_dir"
            )
        return RunDir(path=path, journal=Journal.open(path / "journal.jsonl"), lock=lock)
    except BaseException:
        lock.release()
        raise


def _stored_config(config_path: Path) -> dict[str, Any]:
    todo = "restore it from a backup, or run the evaluation again into a new --output_dir"
    try:
        stored = json.loads(config_path.read_text(encoding="utf-8"))
    except OSError as error:
        raise RunDirError(f"--resume: cannot read {config_path} ({error.strerror}); {todo}") from None
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise RunDirError(f"--resume: {config_path} is not valid JSON; {todo}") from None
    if not isinstance(stored, dict):
        raise RunDirError(f"--resume: {config_path} holds no settings (not a JSON object); {todo}")
    return stored


def _create(path: Path, config: dict[str, Any], holder: str) -> RunDir:
    if path.exists() and not path.is_dir():
        raise RunDirError(f"--output_dir: {path} is a file; choose a directory")
    existed = path.exists()
    if existed and any(path.iterdir()):
        raise _exists(path)
    lock = None
    try:
        path.mkdir(parents=True, exist_ok=True)
        lock = RunLock.acquire(path, holder)
        if (path / "config.json").exists():  # another writer set it up between our look and our lock
            lock.release()
            raise _exists(path)
        write_json_atomic(path / "config.json", config)
        return RunDir(path=path, journal=Journal.open(path / "journal.jsonl"), lock=lock)
    except OSError as error:
        _remove_created(path, existed, lock)
        if no_space(error):
            raise DiskFullError(f"no space left on the disk holding {path}; free space and run again") from None
        raise RunDirError(
            f"--output_dir: cannot write to {path} ({error.strerror}); choose a writable directory"
        ) from None


def _exists(path: Path) -> RunDirError:
    return RunDirError(
        f"--output_dir: {path} already exists; pass --resume=true to continue that run or choose a new directory"
    )


def _remove_created(path: Path, existed: bool, lock: RunLock | None) -> None:
    """Leave nothing of a run directory that could not be set up."""
    if lock is not None:
        lock.release()
    if not path.is_dir():
        return
    for name in ("journal.jsonl", "config.json", LOCK_FILE):
        (path / name).unlink(missing_ok=True)
    if not existed and not any(path.iterdir()):
        path.rmdir()
