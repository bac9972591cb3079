"""Parsing the physical side of a task file: workspace (bounds, units, regions), objects and the cost model."""

from __future__ import annotations

import math
import re

from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.domains.task_file.nodes import Node
from lerobot_contrast.domains.task_file.schema import ROBOT, CostSpec, ObjectSpec, Region, Workspace

UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001}
ATTRIBUTES = ("colour", "shape", "size", "category")
NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*$")
DEFAULT_MIN_SPACING_M = 0.05
INTERVAL = "[min, max] with min < max"
POINT = "[x, y]"
POSE = "[x, y] or [x, y, yaw in degrees]"


def check_name(node: Node, name: str, what: str) -> None:
    if not NAME.match(name) or name == ROBOT:
        node.fail(
            f"{what} name {name!r} must be an identifier (letters, digits, _) other than {ROBOT!r}; "
            "put the words people say in `words:`"
        )


def interval(node: Node, scale: float) -> tuple[float, float]:
    low, high = node.numbers((2,), INTERVAL)
    if not low < high:
        node.fail(f"expected {INTERVAL}, got [{low:g}, {high:g}]")
    return low * scale, high * scale


def point(node: Node, scale: float) -> tuple[float, float]:
    x, y = node.numbers((2,), POINT)
    return x * scale, y * scale


def pose(node: Node, scale: float) -> Pose:
    x, y, *yaw = node.numbers((2, 3), POSE)
    return Pose(x * scale, y * scale, math.radians(yaw[0]) if yaw else 0.0)


def inside(workspace: Region, region: Region) -> bool:
    (x0, x1), (y0, y1) = region.box
    (wx0, wx1), (wy0, wy1) = workspace.box
    return wx0 <= x0 and x1 <= wx1 and wy0 <= y0 and y1 <= wy1


def words_of(node: Node | None, default: tuple[str, ...]) -> tuple[str, ...]:
    if node is None:
        return default
    words = node.texts()
    if len(set(words)) < len(words):
        node.fail("expected distinct words; remove the repeated entry")
    return words


def parse_region(name: str, node: Node, scale: float, workspace: Region) -> Region:
    node.check_keys(("center", "radius", "x", "y", "words"))
    check_name(node, name, "region")
    words = words_of(node.get("words"), (name.replace("_", " "),))
    if node.get("center") is not None or node.get("radius") is not None:
        if node.get("x") is not None or node.get("y") is not None:
            node.fail("a region is either a disc (center, radius) or a box (x, y), not both")
        center = point(node.require("center", f"the disc's centre {POINT}"), scale)
        radius = node.require("radius", "the disc's radius").number(0.0, strict=True) * scale
        region = Region(name, words, center=center, radius=radius)
    else:
        x = interval(node.require("x", f"the box's x range {INTERVAL} (or give center and radius)"), scale)
        y = interval(node.require("y", f"the box's y range {INTERVAL}"), scale)
        region = Region(name, words, x=x, y=y)
    if not inside(workspace, region):
        (x0, x1), (y0, y1) = workspace.box
        node.fail(
            f"region {name!r} reaches outside the workspace (x {x0 / scale:g}..{x1 / scale:g}, "
            f"y {y0 / scale:g}..{y1 / scale:g} {_unit(scale)}); move or shrink it"
        )
    return region


def _unit(scale: float) -> str:
    return next(unit for unit, factor in UNITS.items() if factor == scale)


def parse_workspace(node: Node) -> Workspace:
    node.check_keys(("units", "bounds", "regions", "min_spacing", "robot_start", "storage", "tray"))
    units_node = node.get("units")
    units = "m" if units_node is None else units_node.choice(UNITS)
    scale = UNITS[units]
    bounds = node.require("bounds", "the workspace's extent, {x: [min, max], y: [min, max]}")
    bounds.check_keys(("x", "y"))
    area = Region(
        "workspace",
        ("workspace",),
        x=interval(bounds.require("x", INTERVAL), scale),
        y=interval(bounds.require("y", INTERVAL), scale),
    )
    regions = {}
    regions_node = node.get("regions")
    for name, child in [] if regions_node is None else regions_node.items():
        regions[name] = parse_region(name, child, scale, area)
    spacing = node.get("min_spacing")
    start = node.get("robot_start")
    robot_start = None if start is None else pose(start, scale)
    if robot_start is not None and not area.contains(robot_start.x, robot_start.y):
        start.fail("the robot's start pose must lie inside the workspace bounds")
    storage = node.get("storage")
    tray = node.get("tray")
    return Workspace(
        units=units,
        area=area,
        min_spacing=DEFAULT_MIN_SPACING_M if spacing is None else spacing.number(0.0) * scale,
        regions=regions,
        robot_start=robot_start,
        storage=None if storage is None else _storage(storage, scale, area),
        tray=None if tray is None else _tray(tray, scale, area, regions),
    )


def _tray(node: Node, scale: float, area: Region, regions: dict[str, Region]) -> Region:
    """A box inside the bounds where spare objects wait, seen by the camera and reached by an arm that stages."""
    if node.get("center") is not None or node.get("radius") is not None:
        node.fail("the tray is a box {x: [min, max], y: [min, max]}")
    tray = parse_region("tray", node, scale, area)
    for name, region in regions.items():
        if overlaps(tray, region):
            node.fail(f"the tray overlaps region {name!r}; objects waiting in it would count as placed there")
    return tray


def overlaps(a: Region, b: Region) -> bool:
    """Whether the bounding boxes of `a` and `b` share any area."""
    (ax0, ax1), (ay0, ay1) = a.box
    (bx0, bx1), (by0, by1) = b.box
    return ax0 < bx1 and bx0 < ax1 and ay0 < by1 and by0 < ay1


def diagonal(area: Region) -> float:
    (x0, x1), (y0, y1) = area.box
    return math.hypot(x1 - x0, y1 - y0)


def _storage(node: Node, scale: float, area: Region) -> tuple[tuple[float, float], tuple[float, float]]:
    """Two points beside the workspace: further than its own size away, every first trial's cost is absurd."""
    if not isinstance(node.value, list) or len(node.value) != 2:
        node.fail("expected two points [[x, y], [x, y]]: the objects wait in a row between them")
    points = [point(child, scale) for child in node.elements()]
    (x0, x1), (y0, y1) = area.box
    reach = diagonal(area)
    for child, (x, y) in zip(node.elements(), points, strict=True):
        if math.hypot(max(x0 - x, 0.0, x - x1), max(y0 - y, 0.0, y - y1)) > reach:
            child.fail(
                f"the storage point lies further from the workspace than its size ({reach / scale:.3g} "
                f"{_unit(scale)}); objects wait beside the workspace, so put it nearer"
            )
    return points[0], points[1]


def default_words(name: str, attributes: dict[str, str]) -> tuple[str, ...]:
    """'<colour> <shape>', '<colour> <category>', '<size> <colour> <shape>' from what is given."""
    colour, size = attributes.get("colour"), attributes.get("size")
    nouns = [attributes[k] for k in ("shape", "category") if k in attributes]
    if not nouns:
        return (" ".join(filter(None, (colour, name.replace("_", " ")))),)
    words = [" ".join(filter(None, (colour, noun))) for noun in nouns]
    if size:
        words.append(" ".join(filter(None, (size, colour, nouns[0]))))
    return tuple(dict.fromkeys(words))


def parse_object(name: str, node: Node, workspace: Workspace) -> ObjectSpec:
    node.check_keys((*ATTRIBUTES, "words", "movable", "spare", "at", "area"))
    check_name(node, name, "object")
    if name in workspace.regions:
        node.fail(f"{name!r} is already a region; objects and regions need distinct names")
    attributes = {key: node.require(key, "").text() for key in ATTRIBUTES if node.get(key) is not None}
    words = words_of(node.get("words"), default_words(name, attributes))
    movable = True if node.get("movable") is None else node.get("movable").boolean()
    spare = False if node.get("spare") is None else node.get("spare").boolean()
    at, area = node.get("at"), node.get("area")
    scale = UNITS[workspace.units]
    if movable and at is not None:
        at.fail("only fixed objects (movable: false) have a fixed place; the sampler or instances place movable ones")
    if not movable and at is None:
        node.fail(f"missing key 'at': where the fixed object stands, {POSE}")
    if not movable and (spare or area is not None):
        node.fail("a fixed object (movable: false) cannot be spare or have an area")
    pose_at = None if at is None else pose(at, scale)
    if pose_at is not None and not workspace.area.contains(pose_at.x, pose_at.y):
        at.fail("the fixed object must stand inside the workspace bounds")
    if area is not None and area.text() not in workspace.regions:
        area.fail(f"unknown region {area.value!r}; declare it under workspace.regions")
    return ObjectSpec(name, attributes, words, movable, spare, pose_at, None if area is None else area.value)


def parse_objects(node: Node, workspace: Workspace) -> dict[str, ObjectSpec]:
    if not node.mapping():
        node.fail("expected at least one object")
    objects = {name: parse_object(name, child, workspace) for name, child in node.items()}
    tray = workspace.tray
    for name, child in node.items():
        spot = workspace.area if objects[name].area is None else workspace.regions[objects[name].area]
        if tray is not None and objects[name].movable and overlaps(tray, spot):
            child.fail(
                f"{name!r} may be placed in the tray ({'the whole workspace' if objects[name].area is None else spot.name}"
                " overlaps it); give it an area apart from the tray"
            )
    said: dict[str, str] = {}
    for name, child in node.items():
        for word in objects[name].words:
            if word in said:
                child.fail(
                    f"objects {said[word]!r} and {name!r} are both called {word!r}, so instructions would be "
                    "ambiguous; give them different attributes or `words:`"
                )
            said[word] = name
    return objects


def parse_cost(node: Node | None, workspace: Workspace, objects: dict[str, ObjectSpec]) -> CostSpec:
    if node is None:
        return CostSpec()
    node.check_keys(("tolerance", "add_remove", "hand_speed", "handling_time_s"))
    scale, spec = UNITS[workspace.units], CostSpec()
    handling, default = {}, spec.default_handling_s
    times = node.get("handling_time_s")
    for name, child in [] if times is None else times.items():
        seconds = child.number(0.0)
        if name == "default":
            default = seconds
        elif name not in objects:
            child.fail(f"unknown object {name!r}; expected an object name or 'default'")
        else:
            handling[name] = seconds

    def length(key: str, fallback: float, strict: bool = False) -> float:
        child = node.get(key)
        return fallback if child is None else child.number(0.0, strict=strict) * scale

    tolerance = length("tolerance", spec.tolerance)
    if tolerance >= diagonal(workspace.area):
        node.get("tolerance").fail(
            f"a tolerance of {tolerance / scale:g} {workspace.units} is as large as the whole workspace, so no move "
            "would ever count; give the displacement (in the workspace units) below which a move is free"
        )
    return CostSpec(
        tolerance=tolerance,
        add_remove=length("add_remove", spec.add_remove),
        hand_speed=length("hand_speed", spec.hand_speed, strict=True),
        default_handling_s=default,
        handling_s=handling,
    )
