"""The benchmark's word lists: verbs, prepositions, location/direction synonyms, templates, block names.
Opposite lists are index-aligned, so a flip keeps the matching synonym ("upper left" -> "lower right").
"""

from __future__ import annotations

from lerobot_contrast.domains.language_table import board

PUSH_VERBS = ("push the", "move the", "slide the", "put the")
PREPOSITIONS = ("to the", "towards the", "close to the", "next to the")

# block2absolutelocation: "{verb} {block} to the {location}"
LOCATION_SYNONYMS = {
    "top": ("top side", "top", "towards your base"),
    "top_left": ("top left of the board", "top left", "upper left corner", "top left corner"),
    "top_right": ("top right of the board", "top right", "upper right corner", "top right corner"),
    "center": ("middle of the board", "center of the board", "center", "middle"),
    "center_left": ("left side of the board", "center left", "left side"),
    "center_right": ("right side of the board", "center right", "right side"),
    "bottom": ("bottom side", "bottom"),
    "bottom_left": ("bottom left of the board", "bottom left", "lower left corner", "bottom left corner"),
    "bottom_right": ("bottom right of the board", "bottom right", "lower right corner", "bottom right corner"),
}
LOCATION_FLIP = {
    "top": "bottom",
    "bottom": "top",
    "top_left": "bottom_right",
    "bottom_right": "top_left",
    "top_right": "bottom_left",
    "bottom_left": "top_right",
    "center_left": "center_right",
    "center_right": "center_left",
}

DIRECTION_FLIP = {
    "up": "down",
    "down": "up",
    "left": "right",
    "right": "left",
    "diagonal_up_left": "diagonal_down_right",
    "diagonal_down_right": "diagonal_up_left",
    "diagonal_up_right": "diagonal_down_left",
    "diagonal_down_left": "diagonal_up_right",
}

# block2relativelocation
RELATIVE_VERBS = ("move the", "push the", "slide the")
RELATIVE_DIRECTION_SYNONYMS = {
    "up": ("up", "upwards"),
    "down": ("down", "downwards"),
    "left": ("to the left", "left"),
    "right": ("to the right", "right"),
}
DIAGONAL_TEMPLATES = ("{v} and {h}", "{v} and then {h}", "diagonally {v} and {h}", "{v} and {h} diagonally")
SLIGHTLY_SYNONYMS = ("slightly", "a bit", "a little", "a little bit", "somewhat")
# How a "near" (slightly) instruction is phrased; "plain" is the far form without a hedge.
RELATIVE_MODES = {
    "plain": "{verb} {block} {direction}",
    "slightly_first": "slightly {verb} {block} {direction}",
    "prefix": "{verb} {block} {slightly} {direction}",
    "suffix": "{verb} {block} {direction} {slightly}",
}
NEAR_MODES = ("slightly_first", "prefix", "suffix")

# block2blockrelativelocation: "{verb} {block} {direction} {target}"
B2B_RELATIVE_SYNONYMS = {
    "up": ("above the", "to the top side of the", "to the top of the"),
    "down": ("below the", "to the bottom side of the", "to the bottom of the"),
    "left": ("just left of the", "to the left of the", "left of the", "to the left side of the"),
    "right": ("just right of the", "to the right of the", "right of the", "to the right side of the"),
    "diagonal_up_left": (
        "to the top left side of the",
        "to the top left of the",
        "diagonally up and to the left of the",
    ),
    "diagonal_up_right": (
        "to the top right side of the",
        "to the top right of the",
        "diagonally up and to the right of the",
    ),
    "diagonal_down_left": (
        "to the bottom left side of the",
        "to the bottom left of the",
        "diagonally down and to the left of the",
    ),
    "diagonal_down_right": (
        "to the bottom right side of the",
        "to the bottom right of the",
        "diagonally down and to the right of the",
    ),
}

# separate
SEPARATE_TEMPLATES = (
    "pull the {block} apart from the {avoid}",
    "move the {block} away from the {avoid}",
    "separate the {block} from the {avoid}",
)
GROUP_SYNONYMS = ("group", "clump", "group of blocks")
# The benchmark also defines "rest of the blocks" for "all other blocks", but later branches always
# overwrite it, so it never reaches an instruction; we leave it out for the same distribution.


def block_synonyms(name: str, blocks_on_table) -> tuple[str, ...]:
    """Referring expressions for a block: "<color> block" / "<shape>" when unique on the table, and always
    "<color> <shape>". With BLOCK_8 (two of each colour and shape) only the last is ever possible."""
    this = board.block(name)
    others = [board.block(b) for b in blocks_on_table if b != name]
    refs = []
    if all(o.color != this.color for o in others):
        refs.append(f"{this.color} block")
    if all(o.shape != this.shape for o in others):
        refs.append(this.shape)
    refs.append(this.text)
    return tuple(refs)


def matching(options: tuple[str, ...], word: str, new_options: tuple[str, ...]) -> str | None:
    """The synonym in `new_options` at the index `word` has in `options` (None when it has no match)."""
    i = options.index(word)
    return new_options[i] if i < len(new_options) else None
