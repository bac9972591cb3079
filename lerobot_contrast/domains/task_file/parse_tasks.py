"""Parsing the evaluation side of a task file: instruction templates with slots and goals, and listed instances."""

from __future__ import annotations

import string
from collections.abc import Mapping
from dataclasses import dataclass

from lerobot_contrast.contrast.task import OUTCOME_MODES
from lerobot_contrast.domains.task_file.goals import ground_predicate, holds
from lerobot_contrast.domains.task_file.nodes import Node
from lerobot_contrast.domains.task_file.parse_world import ATTRIBUTES, UNITS, check_name, pose
from lerobot_contrast.domains.task_file.schema import (
    ROBOT,
    ListedInstance,
    ObjectSpec,
    Predicate,
    Slot,
    Template,
    Workspace,
)
from lerobot_contrast.domains.task_file.world import listed_scene

STRAIGHT_LINE = "straight_line"


@dataclass(frozen=True)
class World:
    """What templates and instances are checked against: the workspace, the objects and the outcome."""

    workspace: Workspace
    objects: Mapping[str, ObjectSpec]
    mode: str  # outcome mode
    reference: float | str | None  # default SPL reference

    @property
    def scale(self) -> float:
        return UNITS[self.workspace.units]


def text_fields(node: Node, text: str) -> list[str]:
    """The {slot} fields of `text`; anything else in braces is an error."""
    try:
        parsed = list(string.Formatter().parse(text))
    except ValueError as error:
        node.fail(f"unbalanced braces in {text!r} ({error}); write slots as {{name}}")
    fields = []
    for _, name, spec, conversion in parsed:
        if name is None:
            continue
        if not name or spec or conversion or not name.isidentifier():
            node.fail(f"{{{name}}} in {text!r} is not a slot; write slots as {{name}} with a declared slot name")
        fields.append(name)
    return fields


def parse_slot(name: str, node: Node, world: World) -> Slot:
    check_name(node, name, "slot")
    if isinstance(node.value, dict):
        node.check_keys(ATTRIBUTES)
        wanted = {key: set(child.texts()) for key, child in node.items()}
        names = tuple(n for n, o in world.objects.items() if all(o.attributes.get(k) in v for k, v in wanted.items()))
        if not names:
            node.fail("no object has these attributes; check the spelling against `objects:`")
        return Slot(name, "object", names)
    names = node.texts()
    items = node.elements() if isinstance(node.value, list) else [node]
    for item, value in zip(items, names, strict=True):
        if value not in world.objects and value not in world.workspace.regions:
            item.fail(f"unknown object or region {value!r}; declare it under objects or workspace.regions")
    kinds = {"object" if value in world.objects else "region" for value in names}
    if len(kinds) > 1:
        node.fail("a slot takes either objects or regions, not both; split it into two slots")
    return Slot(name, kinds.pop(), tuple(dict.fromkeys(names)))


def _goal_name(node: Node, slots: Mapping[str, Slot], kind: str, world: World, subject: bool = False) -> str:
    value = node.text()
    if value.startswith("{") and value.endswith("}"):
        slot = slots.get(value[1:-1])
        if slot is None:
            node.fail(f"{value} is not a slot of this template; declare it under slots")
        if slot.kind != kind:
            node.fail(
                f"{value} holds {slot.kind}s, but this key expects {'a region' if kind == 'region' else 'an object'}"
            )
        return value
    known = world.workspace.regions if kind == "region" else world.objects
    if value not in known and not (subject and value == ROBOT):
        expected = "a region" if kind == "region" else "an object" + (f" (or {ROBOT!r})" if subject else "")
        node.fail(f"unknown name {value!r}; expected {expected} or a {{slot}}")
    return value


def parse_goal(node: Node, slots: Mapping[str, Slot], world: World) -> Predicate:
    node.check_keys(("subject", "in", "near", "within"))
    subject_node = node.require("subject", f"the object (or {ROBOT!r}) whose pose decides success")
    subject = _goal_name(subject_node, slots, "object", world, subject=True)
    region, near = node.get("in"), node.get("near")
    if (region is None) == (near is None):
        node.fail("expected exactly one of `in: <region>` or `near: <object>` (with `within: <distance>`)")
    if region is not None:
        if node.get("within") is not None:
            node.get("within").fail("`within` goes with `near`; a region's own extent decides `in`")
        return Predicate(subject, region=_goal_name(region, slots, "region", world))
    within = node.require("within", "how close (in the workspace units) counts as near").number(0.0, strict=True)
    target = _goal_name(near, slots, "object", world)
    if target == subject:
        near.fail("the subject cannot be near itself; name another object")
    return Predicate(subject, near=target, within=within * world.scale)


def parse_reference(node: Node | None, default: float | str | None, scale: float) -> float | str | None:
    if node is None:
        return default
    if node.value == STRAIGHT_LINE:
        return STRAIGHT_LINE
    if isinstance(node.value, str):
        node.fail(f"expected {STRAIGHT_LINE!r} or a length in the workspace units")
    return node.number(0.0, strict=True) * scale


def check_template(node: Node, text_key: str, template: Template, mode: str) -> None:
    """Every text says every slot; subgoals use only slots; the outcome mode can judge the template."""
    texts = node.get(text_key)
    slots = set(template.slots)
    for text in template.texts:
        used = set(text_fields(texts, text))
        if used - slots:
            texts.fail(f"{{{sorted(used - slots)[0]}}} in {text!r} is not declared under slots")
        if slots - used:
            texts.fail(f"slot {sorted(slots - used)[0]!r} is declared but {text!r} never says it; use it or drop it")
    for subgoal in template.subgoals:
        unknown = set(text_fields(node.get("subgoals"), subgoal)) - slots
        if unknown:
            node.get("subgoals").fail(f"{{{sorted(unknown)[0]}}} in subgoal {subgoal!r} is not a slot of this template")
    if mode == "predicate" and template.goal is None:
        node.fail(
            f"outcome mode is predicate but {template.key!r} has no `goal:`; add one or set outcome: {{mode: label}}"
        )
    if mode == "subgoals" and not template.subgoals:
        node.fail(f"outcome mode is subgoals but {template.key!r} has no `subgoals:`; list them in order")


def _template(node: Node, key: str, family: Node | None, text_key: str, slots, world: World) -> Template:
    goal, subgoals, weight = node.get("goal"), node.get("subgoals"), node.get("weight")
    template = Template(
        key=key,
        family=(key if text_key == "text" else "listed") if family is None else family.text(),
        texts=node.require(text_key, "the instruction, with {slot} fields").texts(),
        slots=slots,
        goal=None if goal is None else parse_goal(goal, slots, world),
        subgoals=() if subgoals is None else subgoals.texts(),
        reference=parse_reference(node.get("reference"), world.reference, world.scale),
        weight=1.0 if weight is None else weight.number(0.0, strict=True),
    )
    check_template(node, text_key, template, world.mode)
    return template


def parse_templates(node: Node | None, world: World) -> dict[str, Template]:
    templates: dict[str, Template] = {}
    for child in [] if node is None else node.elements():
        child.check_keys(("name", "family", "text", "slots", "goal", "subgoals", "reference", "weight"))
        key = child.require("name", "a short name for the template, e.g. place").text()
        check_name(child.get("name"), key, "template")
        if key in templates:
            child.get("name").fail(f"template {key!r} is declared twice; names must be unique")
        slots_node = child.get("slots")
        slots = {n: parse_slot(n, s, world) for n, s in ([] if slots_node is None else slots_node.items())}
        templates[key] = _template(child, key, child.get("family"), "text", slots, world)
    return templates


def _instance_slots(node: Node, template: Template, placements: Mapping) -> dict[str, str]:
    slots_node = node.get("slots")
    given = {} if slots_node is None else dict(slots_node.items())
    for name, child in given.items():
        slot = template.slots.get(name)
        if slot is None:
            child.fail(f"template {template.key!r} has no slot {name!r}; its slots: {', '.join(template.slots)}")
        if child.text() not in slot.candidates:
            child.fail(
                f"{child.value!r} is not allowed in slot {name!r}; expected one of: {', '.join(slot.candidates)}"
            )
        if slot.kind == "object" and child.value not in placements:
            child.fail(f"{child.value!r} is not placed in this instance; add it to placements")
    missing = [name for name in template.slots if name not in given]
    if missing:
        node.fail(f"missing slot {missing[0]!r} for template {template.key!r}; give slots: {{{missing[0]}: ...}}")
    return {name: child.value for name, child in given.items()}


def _placements(node: Node, world: World) -> dict:
    placements = {}
    for name, child in node.items():
        obj = world.objects.get(name)
        if obj is None:
            child.fail(f"unknown object {name!r}; declare it under objects")
        if not obj.movable:
            child.fail(f"{name!r} is fixed (movable: false); its place is its `at`")
        placements[name] = pose(child, world.scale)
        if not world.workspace.area.contains(placements[name].x, placements[name].y):
            child.fail(f"{name!r} is placed outside the workspace bounds")
    missing = [n for n, o in world.objects.items() if o.movable and not o.spare and n not in placements]
    if missing:
        node.fail(f"missing placement for {missing[0]!r}; place every movable object not marked spare")
    return placements


def parse_instance(node: Node, index: int, templates: Mapping[str, Template], world: World) -> ListedInstance:
    keys = ("template", "slots", "instruction", "family", "goal", "subgoals", "reference", "placements", "robot")
    node.check_keys(keys)
    placements = _placements(node.require("placements", "where each movable object stands, {name: [x, y]}"), world)
    if (node.get("template") is None) == (node.get("instruction") is None):
        node.fail("expected either `template:` with `slots:`, or `instruction:` with `goal:`")
    if node.get("template") is not None:
        name = node.get("template").text()
        if name not in templates:
            node.get("template").fail(
                f"unknown template {name!r}; declared templates: {', '.join(templates) or 'none'}"
            )
        template, slots = templates[name], _instance_slots(node, templates[name], placements)
    else:
        if node.get("slots") is not None:
            node.get("slots").fail("slots go with `template:`; a listed `instruction:` is said as written")
        template = _template(node, f"instances[{index}]", node.get("family"), "instruction", {}, world)
        slots = {}
    robot = node.get("robot")
    robot_pose = world.workspace.robot_start if robot is None else pose(robot, world.scale)
    listed = ListedInstance(template, slots, placements, robot_pose)
    if holds(ground_predicate(template.goal, slots), listed_scene(listed, world.objects), world.workspace.regions):
        node.fail("the goal already holds in these placements, so the trial would test nothing; move the objects")
    return listed


def parse_instances(node: Node, templates: Mapping[str, Template], world: World) -> tuple[ListedInstance, ...]:
    if not node.sequence():
        node.fail("expected at least one instance")
    return tuple(parse_instance(child, i, templates, world) for i, child in enumerate(node.elements()))


def parse_outcome(node: Node | None, scale: float) -> tuple[str, float | str | None]:
    """The outcome mode and the default reference for SPL."""
    if node is None:
        return "predicate", None
    node.check_keys(("mode", "reference"))
    mode = node.get("mode")
    return (
        "predicate" if mode is None else mode.choice(OUTCOME_MODES),
        parse_reference(node.get("reference"), None, scale),
    )
