"""The console's structured channel: each prompt (and the start of each episode) as one JSON line, so that a program
answering the console (the twin's scripted person) reads what it asks, never its screen text. Answers still go in as
a person types them, so a person can take over at any prompt.

    {"version": 1, "event": "trial", "trial": 0, "of": 3, "instruction": "...", "moves": {...}, "instance": {...}}
        (each trial's start: the instance the evaluator runs, its scene the targets it stages)
    {"version": 1, "prompt": "stage", "trial": 0, "of": 3, "instruction": "...", "moves": {"red_cube": [x, y] | null}}
    {"version": 1, "prompt": "check", "off": {"red_cube": 0.041 | null}, "tolerance": 0.02}
    {"version": 1, "event": "running"}
    {"version": 1, "prompt": "label", "trial": 0, "instruction": "...", "subgoals": [...]}
    {"version": 1, "prompt": "aborted", "reason": "emergency stop"}
    {"version": 1, "prompt": "call", "trial": 0, "trouble": "...", "fix": {"red_cube": [x, y] | null}}  (the arm)
    {"version": 1, "event": "ended", "trial": 0}  (the arm: the episode ended, before it lets go or moves)
    {"version": 1, "event": "labelled", "trial": 0, "success": true, "sure": true, "held": []}  (the arm's own label)
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import IO, Any

from lerobot_contrast.contrast.errors import UserError

VERSION = 1


class Channel:
    """Writes the console's prompts as JSON lines to `path` (a file, a FIFO or /dev/fd/N)."""

    def __init__(self, path: str | Path) -> None:
        try:
            self._out: IO[str] = open(path, "w", encoding="utf-8", buffering=1)  # noqa: SIM115
        except OSError as error:
            raise UserError(f"--operator_channel={path}: cannot open it ({error.strerror})") from None

    def send(self, **message: Any) -> None:
        try:
            self._out.write(json.dumps({"version": VERSION, **message}) + "\n")
        except (BrokenPipeError, OSError):  # the program reading it went away: a person may still answer
            return


def parse(line: str) -> dict[str, Any] | None:
    """One channel line as a message, or None where it is not one of this version's."""
    try:
        message = json.loads(line)
    except json.JSONDecodeError:
        return None
    return message if isinstance(message, dict) and message.get("version") == VERSION else None
