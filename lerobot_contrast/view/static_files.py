"""The page's own files (package data in static/) and the form its data takes: scripts that hand a document to the
page, which a browser loads from a server and from a folder opened as a file alike."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

STATIC = Path(__file__).with_name("static")


def static_files() -> list[Path]:
    return sorted(p for p in STATIC.iterdir() if p.is_file())


def script(callback: str, doc: Any) -> str:
    """`doc` as a script calling `callback`: a script tag loads it where fetch() is refused (a page opened from
    disk). "</" is escaped so no string closes an inline script."""
    return f"{callback}({json.dumps(doc, separators=(',', ':')).replace('</', '<\\/')});\n"
