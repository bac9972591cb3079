"""The apartment's furniture catalogue: footprint shape and size, height and colour of each category."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass


@dataclass(frozen=True)
class Furniture:
    """A furniture category. Boxes are `length` along their local x axis (the pose's yaw) by `width`;
    cylinders have diameter `length` (== `width`)."""

    category: str
    shape: str  # "box" | "cylinder"
    length: float
    width: float
    height: float
    color: tuple[int, int, int]


# The categories the paper's participants arranged (bed, couch, lamp, plant, bookshelf, table, chair,
# TV stand) plus a desk and a dresser. Sizes are typical for a studio apartment.
CATALOG: dict[str, Furniture] = {
    f.category: f
    for f in (
        Furniture("bed", "box", 2.0, 1.4, 0.55, (72, 110, 178)),
        Furniture("couch", "box", 1.9, 0.85, 0.85, (164, 72, 56)),
        Furniture("lamp", "cylinder", 0.35, 0.35, 1.6, (236, 206, 92)),
        Furniture("plant", "cylinder", 0.5, 0.5, 1.1, (56, 148, 64)),
        Furniture("bookshelf", "box", 1.0, 0.35, 1.8, (122, 84, 48)),
        Furniture("table", "box", 1.2, 0.8, 0.75, (206, 172, 118)),
        Furniture("chair", "box", 0.5, 0.5, 0.9, (96, 96, 104)),
        Furniture("tv_stand", "box", 1.4, 0.45, 1.1, (44, 44, 52)),
        Furniture("desk", "box", 1.2, 0.6, 0.75, (226, 226, 220)),
        Furniture("dresser", "box", 1.0, 0.5, 1.0, (168, 116, 158)),
    )
}

# The studio as furnished (x along the 8 m wall, origin in a corner): where the simulator starts, and the
# layout that evaluation arrangements rearrange.
STUDIO: dict[str, tuple[float, float, float]] = {
    "bed": (6.8, 4.9, 0.0),
    "dresser": (7.7, 2.6, math.pi / 2),
    "tv_stand": (2.6, 5.7, 0.0),
    "couch": (2.6, 3.4, 0.0),
    "lamp": (4.6, 5.6, 0.0),
    "plant": (0.45, 5.5, 0.0),
    "bookshelf": (0.25, 1.8, math.pi / 2),
    "table": (5.0, 1.5, 0.0),
    "chair": (3.9, 1.5, 0.0),
    "desk": (2.2, 0.35, 0.0),
}

_NUMBERED = re.compile(r"^(?P<category>.+)_\d+$")


def furniture_for(name: str) -> Furniture:
    """The category of a scene object: its name, or its name without a `_<n>` suffix (`chair_2`)."""
    if name in CATALOG:
        return CATALOG[name]
    match = _NUMBERED.match(name)
    if match and match["category"] in CATALOG:
        return CATALOG[match["category"]]
    raise ValueError(f"unknown furniture {name!r}; name objects after a category: {', '.join(CATALOG)}")
