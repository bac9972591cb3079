"""Instruction wording: sample the benchmark's phrasing for a goal, render it, and flip its directions.
A goal keeps its wording in `goal["words"]` (slot -> phrase), so a perturbation can edit one slot and re-render.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from lerobot_contrast.domains.language_table import synonyms as syn

Words = dict[str, Any]


def pick(rng: np.random.Generator, options: Sequence[str]) -> str:
    return str(options[int(rng.integers(len(options)))])


def avoid_phrase(avoid_refs: Sequence[str]) -> str:
    """Named avoid blocks as the benchmark lists them: "a", "a and b", "a, b, and c"."""
    if len(avoid_refs) == 1:
        return avoid_refs[0]
    if len(avoid_refs) == 2:
        return f"{avoid_refs[0]} and {avoid_refs[1]}"
    if len(avoid_refs) == 3:
        return f"{avoid_refs[0]}, {avoid_refs[1]}, and {avoid_refs[2]}"
    raise ValueError(f"cannot name {len(avoid_refs)} avoid blocks; use a group word")


def _relative_direction_words(direction: str, rng: np.random.Generator) -> Words:
    parts = direction.removeprefix("diagonal_").split("_")
    vertical = next((p for p in parts if p in ("up", "down")), None)
    horizontal = next((p for p in parts if p in ("left", "right")), None)
    return {
        "vertical": None if vertical is None else pick(rng, syn.RELATIVE_DIRECTION_SYNONYMS[vertical]),
        "horizontal": None if horizontal is None else pick(rng, syn.RELATIVE_DIRECTION_SYNONYMS[horizontal]),
        "diagonal": pick(rng, syn.DIAGONAL_TEMPLATES) if vertical and horizontal else None,
    }


def sample_words(
    family: str, goal: Mapping[str, Any], blocks_on_table, rng: np.random.Generator, free_order: bool = False
) -> Words:
    """Fresh wording for `goal`, drawn like the benchmark's instruction sampler.

    Named avoid blocks are listed nearest first as in the benchmark, or in any order with `free_order`
    (a paraphrase may reorder the list).
    """

    def ref(name: str) -> str:
        return pick(rng, syn.block_synonyms(name, blocks_on_table))

    if family == "block2block":
        return {
            "verb": pick(rng, syn.PUSH_VERBS),
            "block": ref(goal["block"]),
            "preposition": pick(rng, syn.PREPOSITIONS),
            "target": ref(goal["target_block"]),
        }
    if family == "block2absolutelocation":
        return {
            "verb": pick(rng, syn.PUSH_VERBS),
            "block": ref(goal["block"]),
            "location": pick(rng, syn.LOCATION_SYNONYMS[goal["location"]]),
        }
    if family == "block2relativelocation":
        words = {"verb": pick(rng, syn.RELATIVE_VERBS), "block": ref(goal["block"])}
        words |= _relative_direction_words(goal["direction"], rng)
        mode = "plain" if goal["magnitude"] == "far" else pick(rng, syn.NEAR_MODES)
        slightly = pick(rng, syn.SLIGHTLY_SYNONYMS) if mode in ("prefix", "suffix") else None
        return words | {"mode": mode, "slightly": slightly}
    if family == "block2blockrelativelocation":
        return {
            "verb": pick(rng, syn.PUSH_VERBS),
            "block": ref(goal["block"]),
            "direction": pick(rng, syn.B2B_RELATIVE_SYNONYMS[goal["direction"]]),
            "target": ref(goal["target_block"]),
        }
    if family == "separate":
        if goal["avoid_mode"] == "group":
            avoid = pick(rng, syn.GROUP_SYNONYMS)
        else:
            refs = [ref(name) for name in goal["avoid"]]
            order = rng.permutation(len(refs)) if free_order else range(len(refs))
            avoid = avoid_phrase([refs[i] for i in order])
        return {"template": pick(rng, syn.SEPARATE_TEMPLATES), "block": ref(goal["block"]), "avoid": avoid}
    raise ValueError(f"unknown Language-Table family {family!r}")


def render(family: str, words: Mapping[str, Any]) -> str:
    """The instruction text for `words`."""
    if family == "block2block":
        return f"{words['verb']} {words['block']} {words['preposition']} {words['target']}"
    if family == "block2absolutelocation":
        location = words["location"]  # "towards your base" is a direction already: no "to the" before it
        place = location if location.startswith("towards ") else f"to the {location}"
        return f"{words['verb']} {words['block']} {place}"
    if family == "block2relativelocation":
        if words["diagonal"]:
            direction = words["diagonal"].format(v=words["vertical"], h=words["horizontal"])
        else:
            direction = words["vertical"] or words["horizontal"]
        template = syn.RELATIVE_MODES[words["mode"]]
        return template.format(
            verb=words["verb"], block=words["block"], direction=direction, slightly=words["slightly"]
        )
    if family == "block2blockrelativelocation":
        return f"{words['verb']} {words['block']} {words['direction']} {words['target']}"
    if family == "separate":
        return words["template"].format(block=words["block"], avoid=words["avoid"])
    raise ValueError(f"unknown Language-Table family {family!r}")


def _flip_relative_word(word: str | None) -> str | None:
    if word is None:
        return None
    for name, options in syn.RELATIVE_DIRECTION_SYNONYMS.items():
        if word in options:
            flipped = syn.DIRECTION_FLIP[name]
            return syn.matching(options, word, syn.RELATIVE_DIRECTION_SYNONYMS[flipped])
    raise ValueError(f"unknown direction word {word!r}")


def flip_words(family: str, goal: Mapping[str, Any], rng: np.random.Generator) -> Words | None:
    """The wording with directions/locations flipped to the opposite, keeping the matching synonym.

    Uses `rng` only where the opposite has no synonym at the same index ("towards your base" has no
    "bottom" counterpart). None where nothing flips.
    """
    words = dict(goal["words"])
    if family == "block2absolutelocation":
        location = goal["location"]
        if location not in syn.LOCATION_FLIP:
            return None
        options, flipped = syn.LOCATION_SYNONYMS[location], syn.LOCATION_SYNONYMS[syn.LOCATION_FLIP[location]]
        return words | {"location": syn.matching(options, words["location"], flipped) or pick(rng, flipped)}
    if family == "block2relativelocation":
        return words | {k: _flip_relative_word(words[k]) for k in ("vertical", "horizontal")}
    if family == "block2blockrelativelocation":
        direction = goal["direction"]
        flipped = syn.B2B_RELATIVE_SYNONYMS[syn.DIRECTION_FLIP[direction]]
        return words | {"direction": syn.matching(syn.B2B_RELATIVE_SYNONYMS[direction], words["direction"], flipped)}
    return None
