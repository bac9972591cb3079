"""How instructions name furniture and phrase two-subgoal routes; paraphrases keep the meaning (ΔL)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

# The words people use for each furniture category; the first is what the shipped instructions use.
NAMES: dict[str, tuple[str, ...]] = {
    "bed": ("bed",),
    "couch": ("couch", "sofa"),
    "lamp": ("lamp", "floor lamp", "standing lamp"),
    "plant": ("plant", "potted plant"),
    "bookshelf": ("bookshelf", "bookcase", "shelf"),
    "table": ("table", "dining table"),
    "chair": ("chair",),
    "tv_stand": ("TV stand", "television stand", "TV"),
    "desk": ("desk", "writing desk"),
    "dresser": ("dresser", "chest of drawers"),
}

# Two-subgoal phrasings: pass (or reach) {first}, then stop at {final}.
TEMPLATES: tuple[str, ...] = (
    "Go past the {first} and stop at the {final}.",
    "Walk by the {first}, keep going and stop when you reach the {final}.",
    "Head to the {first}, then continue to the {final} and stop there.",
    "First go to the {first}. After that, go to the {final} and stop.",
    "Pass the {first} and then stop next to the {final}.",
    "Move towards the {first}, then make your way to the {final} and wait there.",
    "Make your way over to the {first}, then finish at the {final}.",
)


def name_of(category: str) -> str:
    """The canonical word for a furniture object (`chair_2` is a chair)."""
    base = category if category in NAMES else category.rsplit("_", 1)[0]
    return NAMES.get(base, (category.replace("_", " "),))[0]


def synonyms(category: str) -> tuple[str, ...]:
    base = category if category in NAMES else category.rsplit("_", 1)[0]
    return NAMES.get(base, (name_of(category),))


def render(template: str, words: Mapping[str, str]) -> str:
    return template.format(**words)


def paraphrase(template: str, words: Mapping[str, str], subgoals: list[str], rng: np.random.Generator):
    """Another template and other words for the same objects: (template, words), different from the input."""
    for _ in range(50):
        new_template = TEMPLATES[int(rng.integers(len(TEMPLATES)))]
        new_words = {
            slot: str(rng.choice(synonyms(name))) for slot, name in zip(("first", "final"), subgoals, strict=True)
        }
        if render(new_template, new_words) != render(template, words):
            return new_template, new_words
    return None
