"""A person's audit labels given after the session (`--arm.audit_at=viewer`), in `audit.jsonl` in the run directory:
one JSON line per label, appended by the run viewer while the session may still be appending to its journal (two
files, each with one writer at a time: nothing the session writes is touched). Each line is one `write` to a file
opened for appending, so a line is never interleaved with another; a line cut short by a kill is skipped when read,
and the next label starts a line of its own.
The last label of a trial is the one that counts (a person who changed their mind)."""

from __future__ import annotations

import json
import math
import os
import time
from pathlib import Path
from typing import Any

AUDIT_FILE = "audit.jsonl"


def drawn(extra: dict[str, Any]) -> bool:
    """Whether a journalled trial (its `extra`) was drawn for the audit: its label waits on the audit page
    (`audit_drawn`), or the person gave it live (`audit`)."""
    return bool(extra.get("audit_drawn")) or "audit" in extra


def append_label(run_dir: Path, trial: int, success: bool, seconds: float | None) -> dict[str, Any]:
    """Keep a person's label of `trial`; `seconds`: how long they took to give it after the episode's video ended."""
    line = {"trial": int(trial), "success": bool(success), "at": round(time.time(), 3)}
    if seconds is not None and math.isfinite(seconds) and seconds >= 0:
        line["seconds"] = round(float(seconds), 2)
    data = (json.dumps(line) + "\n").encode("utf-8")
    handle = os.open(Path(run_dir) / AUDIT_FILE, os.O_RDWR | os.O_APPEND | os.O_CREAT, 0o644)
    try:
        size = os.fstat(handle).st_size
        if size and os.pread(handle, 1, size - 1) != b"\n":
            data = b"\n" + data  # after a line a kill cut short: this one starts on its own
        os.write(handle, data)
        os.fsync(handle)
    finally:
        os.close(handle)
    return line


def read_labels(run_dir: Path) -> dict[int, dict[str, Any]]:
    """Each trial's last audit label ({"trial", "success", "at", "seconds"?}), by trial index."""
    path = Path(run_dir) / AUDIT_FILE
    if not path.is_file():
        return {}
    labels: dict[int, dict[str, Any]] = {}
    for text in path.read_text(encoding="utf-8", errors="replace").splitlines():
        try:
            line = json.loads(text)
            labels[int(line["trial"])] = {**line, "success": bool(line["success"])}
        except (json.JSONDecodeError, KeyError, TypeError, ValueError):
            continue  # the tail of a write a kill cut short
    return labels
