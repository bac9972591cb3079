"""Wording: synonym substitution in the fixed words of an instruction template (never inside its {slots})."""

from __future__ import annotations

import re
import string
from collections.abc import Sequence

import numpy as np

Synonyms = tuple[tuple[str, ...], ...]


def pick(rng: np.random.Generator, options: Sequence[str]) -> str:
    return options[int(rng.integers(len(options)))]


def _pattern(synonyms: Synonyms) -> re.Pattern[str]:
    phrases = sorted({p for group in synonyms for p in group}, key=len, reverse=True)
    return re.compile(r"\b(" + "|".join(re.escape(p) for p in phrases) + r")\b")


def _literals(text: str) -> list[tuple[str, str | None]]:
    """(fixed words, slot name or None) pairs of a template text."""
    return [(literal, name) for literal, name, _, _ in string.Formatter().parse(text)]


def mentions(text: str, synonyms: Synonyms) -> bool:
    """Whether any synonym occurs in the fixed words of `text`."""
    if not synonyms:
        return False
    pattern = _pattern(synonyms)
    return any(pattern.search(literal) for literal, _ in _literals(text))


def substitute(text: str, synonyms: Synonyms, rng: np.random.Generator) -> str:
    """`text` with each synonym in its fixed words replaced by a random member of its group (possibly itself)."""
    if not synonyms:
        return text
    group_of = {phrase: group for group in synonyms for phrase in group}
    pattern = _pattern(synonyms)
    out = []
    for literal, name in _literals(text):
        replaced = pattern.sub(lambda m: pick(rng, group_of[m.group(0)]), literal)
        out.append(replaced.replace("{", "{{").replace("}", "}}"))
        if name is not None:
            out.append(f"{{{name}}}")
    return "".join(out)
