"""How LIBERO's instructions name objects and actions, for paraphrases (ΔL) and for naming another object (ΔLB)."""

from __future__ import annotations

import re

# The words LIBERO's instructions use for object categories whose BDDL name differs.
PHRASES = {
    "akita_black_bowl": "black bowl",
    "glazed_rim_porcelain_ramekin": "ramekin",
    "cookies": "cookie box",
    "porcelain_mug": "white mug",
    "white_yellow_mug": "yellow and white mug",
    "red_coffee_mug": "red mug",
    "chefmate_8_frypan": "frying pan",
    "black_book": "book",
    "bbq_sauce": "bbq sauce",
    "new_salad_dressing": "salad dressing",
}

# Rewordings that keep the meaning, as (pattern, alternatives); each is applied at word boundaries.
SYNONYMS = (
    (r"pick up", ("grab", "take")),
    (r"place it", ("put it", "set it")),
    (r"put", ("place", "set")),
    (r"on top of", ("onto",)),
    (r"turn on", ("switch on",)),
    (r"open", ("pull open",)),
    (r"close", ("shut",)),
    (r"push", ("slide",)),
    (r"in the basket", ("into the basket",)),
)


def phrase(category: str) -> str:
    return PHRASES.get(category, category.replace("_", " "))


def find(text: str, pattern: str) -> re.Match | None:
    return re.search(rf"\b{pattern}\b", text)


def mention(text: str, category: str) -> str | None:
    """The words by which `text` names an object of `category` (its usual phrase, else the longest tail of its
    name, e.g. "bowl"), or None when it does not name it."""
    words = category.split("_")
    candidates = [phrase(category), *(" ".join(words[k:]) for k in range(len(words)))]
    for candidate in candidates:
        if find(text, re.escape(candidate)):
            return candidate
    return None


def replace_first(text: str, old: str, new: str) -> str:
    return re.sub(rf"\b{re.escape(old)}\b", new, text, count=1)
