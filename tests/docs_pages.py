"""The README and the documentation pages as text, and the code blocks they show, for the tests that run them."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def text(page: Path) -> str:
    return page.read_text(encoding="utf-8")


def code_blocks(language: str, pages: list[Path] = PAGES) -> list[str]:
    """Every fenced block of `language` in `pages`, indented ones (inside lists) included."""
    pattern = rf"^ *```{language}\n(.*?)^ *```"
    return [block for page in pages for block in re.findall(pattern, text(page), flags=re.S | re.M)]
