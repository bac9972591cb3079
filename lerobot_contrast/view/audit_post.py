"""The audit page's one write: `POST /audit/<run>` with `{"trial": N, "success": true|false, "seconds": S}` keeps a
person's label of a trial the audit drew in the run's audit.jsonl (record/audit_labels.py), beside a session that may
still be appending to the journal.

Only the viewer's own page may write. The server listens on 127.0.0.1 alone; a request must name this viewer as its
Host (a web page whose name resolves to 127.0.0.1 does not: DNS rebinding) and as its Origin (a browser sends the
page's origin with every POST it makes, so a page elsewhere that posts here is told no: cross-site forgery), and send
JSON, which no plain HTML form can. A label for a trial not in the journal, not done, or not drawn is refused with
why, and nothing is written."""

from __future__ import annotations

import json
import math
from http import HTTPStatus
from pathlib import Path
from typing import Any

from lerobot_contrast.record.audit_labels import append_label, drawn
from lerobot_contrast.record.journal import JournalError, read_journal

MAX_BODY = 1024  # bytes: a label is a few dozen


class Refused(Exception):
    def __init__(self, status: HTTPStatus, message: str) -> None:
        super().__init__(message)
        self.status = status


def check_sender(headers: Any, port: int) -> None:
    """Refuse a request that is not the viewer's own page's."""
    hosts = {f"127.0.0.1:{port}", f"localhost:{port}"}
    if headers.get("Host", "") not in hosts:
        raise Refused(HTTPStatus.FORBIDDEN, f"this viewer answers as 127.0.0.1:{port} only")
    if headers.get("Origin", "") not in {f"http://{host}" for host in hosts}:
        raise Refused(HTTPStatus.FORBIDDEN, "labels are taken from the viewer's own audit page only")
    if headers.get("Content-Type", "").split(";")[0].strip() != "application/json":
        raise Refused(HTTPStatus.UNSUPPORTED_MEDIA_TYPE, "send the label as JSON (Content-Type: application/json)")


def take_label(run_dir: Path, body: bytes) -> dict[str, Any]:
    """Check the label in `body` against the run's journal and keep it; returns the line kept."""
    try:
        said = json.loads(body.decode("utf-8"))
        trial, success, seconds = said["trial"], said["success"], said.get("seconds")
        if not isinstance(trial, int) or not isinstance(success, bool):
            raise TypeError
        if seconds is not None and not (isinstance(seconds, int | float) and math.isfinite(seconds)):
            raise TypeError
    except (UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError, AttributeError):
        raise Refused(HTTPStatus.BAD_REQUEST, 'give {"trial": N, "success": true or false, "seconds": S}') from None
    journal = Path(run_dir) / "journal.jsonl"
    try:
        records = read_journal(journal) if journal.is_file() else []
    except JournalError as error:
        raise Refused(HTTPStatus.CONFLICT, f"the run's journal cannot be read ({error})") from None
    record = next((r for r in records if r.index == trial), None)
    if record is None:
        raise Refused(HTTPStatus.NOT_FOUND, f"trial {trial} is not in this run's journal")
    if record.status != "done":
        raise Refused(HTTPStatus.CONFLICT, f"trial {trial} is {record.status}, not done: there is no outcome to label")
    if not drawn(record.extra):
        raise Refused(HTTPStatus.CONFLICT, f"trial {trial} was not drawn for the audit; label only those it drew")
    return append_label(run_dir, trial, success, seconds)
