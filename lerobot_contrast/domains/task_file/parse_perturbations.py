"""Parsing a task file's perturbations: generic kinds with their parameters, custom ones by `module:function`,
and the check that each one can apply to at least one instruction of the evaluation set."""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import sys
from pathlib import Path
from typing import Any

from lerobot_contrast.contrast.perturbation import AXES
from lerobot_contrast.domains.task_file.nodes import Node
from lerobot_contrast.domains.task_file.parse_world import UNITS
from lerobot_contrast.domains.task_file.perturbations import GENERIC, custom_kwargs, swap_pairs
from lerobot_contrast.domains.task_file.schema import PerturbationSpec, TaskSpec, Template
from lerobot_contrast.domains.task_file.wording import mentions

PARAMS = {
    "paraphrase": ("synonyms",),
    "swap_referents": ("slots",),
    "flip": ("pairs",),
    "change_goal": ("slot",),
    "move_distractor": ("min_move", "clearance"),
    "add_remove_distractor": ("mode", "clearance"),
    "move_goal_object": ("slot", "min_move"),
}
ADD_REMOVE_MODES = ("either", "add", "remove")


def used_templates(spec: TaskSpec) -> list[Template]:
    if spec.instances is not None:
        return list({listed.template.key: listed.template for listed in spec.instances}.values())
    return list(spec.templates.values())


def _groups(node: Node, what: str) -> tuple[tuple[str, ...], ...]:
    groups = []
    for child in node.elements():
        group = child.texts()
        if len(set(group)) < 2:
            child.fail(f"expected a list of at least two different {what}")
        groups.append(group)
    return tuple(groups)


def _synonyms(node: Node) -> tuple[tuple[str, ...], ...]:
    groups = _groups(node, "phrases that mean the same, e.g. [put, place]")
    seen: dict[str, int] = {}
    for i, (child, group) in enumerate(zip(node.elements(), groups, strict=True)):
        for phrase in group:
            if phrase in seen and seen[phrase] != i:
                child.fail(f"{phrase!r} is in two synonym groups; merge them or drop it from one")
            seen[phrase] = i
    return groups


def _params(kind: str, node: Node, spec: TaskSpec) -> dict[str, Any]:
    scale, spacing = UNITS[spec.workspace.units], spec.workspace.min_spacing
    known = {**spec.objects, **spec.workspace.regions}
    params: dict[str, Any] = {}
    if kind == "paraphrase":
        params["synonyms"] = () if node.get("synonyms") is None else _synonyms(node.get("synonyms"))
    if kind == "flip":
        pairs_node = node.require("pairs", "pairs of opposite regions or objects, e.g. [[left_bin, right_bin]]")
        pairs = _groups(pairs_node, "names, e.g. [left_bin, right_bin]")
        for child, pair in zip(pairs_node.elements(), pairs, strict=True):
            if len(pair) != 2 or any(name not in known for name in pair):
                child.fail("expected a pair [a, b] of declared regions or objects")
        params["pairs"] = pairs
    if kind == "swap_referents":
        slots = node.get("slots")
        if slots is not None and (not isinstance(slots.value, list) or len(slots.texts()) != 2):
            slots.fail("expected two slot names, e.g. [object, target]")
        params["slots"] = None if slots is None else slots.texts()
    if kind in ("change_goal", "move_goal_object"):
        params["slot"] = None if node.get("slot") is None else node.get("slot").text()
    if kind in ("move_distractor", "move_goal_object"):
        params["min_move"] = spacing if node.get("min_move") is None else node.get("min_move").number(0.0) * scale
    if kind in ("move_distractor", "add_remove_distractor"):
        params["clearance"] = spacing if node.get("clearance") is None else node.get("clearance").number(0.0) * scale
    if kind == "add_remove_distractor":
        params["mode"] = "either" if node.get("mode") is None else node.get("mode").choice(ADD_REMOVE_MODES)
    return params


def _free_objects(template: Template, spec: TaskSpec) -> int:
    """How many evaluation-set objects an instruction from `template` never involves (at most)."""
    busy = sum(slot.kind == "object" for slot in template.slots.values())
    goal = template.goal
    literal = [] if goal is None else [n for n in (goal.subject, goal.near) if n in spec.objects]
    return len(spec.placed) - busy - len([n for n in literal if n in spec.placed])


def _moves_goal_object(template: Template, slot: str | None, spec: TaskSpec) -> bool:
    def movable(name: str | None) -> bool:
        if name is not None and name.startswith("{"):
            s = template.slots[name[1:-1]]
            return s.kind == "object" and any(spec.objects[c].movable for c in s.candidates)
        return name in spec.objects and spec.objects[name].movable

    if slot is not None:
        return slot in template.slots and movable(f"{{{slot}}}")
    return template.goal is not None and (movable(template.goal.subject) or movable(template.goal.near))


def never_applies(kind: str, params: dict[str, Any], spec: TaskSpec) -> str | None:
    """Why perturbation `kind` cannot apply to any instruction of the evaluation set, or None when it can."""
    templates = used_templates(spec)
    if kind == "paraphrase":
        syn = params["synonyms"]
        if any(
            len(t.texts) > 1
            or any(mentions(text, syn) for text in t.texts)
            or any(len(spec.words(v)) > 1 for s in t.slots.values() for v in s.candidates)
            for t in templates
        ):
            return None
        return "no synonym occurs in an instruction, no template has another text, and every referent has one word"
    if kind == "swap_referents":
        if any(swap_pairs(t, params["slots"]) for t in templates):
            return None
        return "no template has two slots of the same kind that can trade values"
    if kind == "flip":
        slots = [s for t in templates for s in t.slots.values()]
        if any(a in s.candidates and b in s.candidates for s in slots for a, b in params["pairs"]):
            return None
        return "no template slot can take both names of any pair"
    if kind == "change_goal":
        wanted = params["slot"]
        if any(len(s.candidates) > 1 for t in templates for n, s in t.slots.items() if wanted in (None, n)):
            return None
        return f"no template has {'slot ' + repr(wanted) if wanted else 'a slot'} with more than one candidate"
    if kind == "move_distractor" or (kind == "add_remove_distractor" and params["mode"] == "remove"):
        return None if any(_free_objects(t, spec) > 0 for t in templates) else "every object is involved in the goal"
    if kind == "add_remove_distractor":
        spares = any(o.spare for o in spec.objects.values())
        if spares or (params["mode"] == "either" and any(_free_objects(t, spec) > 0 for t in templates)):
            return None
        return "no object is marked spare: true (to add) and every object is involved in the goal (to remove)"
    if any(_moves_goal_object(t, params["slot"], spec) for t in templates):
        return None
    return "no template's goal is about a movable object"


def _import(node: Node, module_name: str, base_dir: Path | None):
    try:
        return importlib.import_module(module_name)
    except ModuleNotFoundError as error:
        if error.name not in (module_name, module_name.split(".")[0]):
            node.fail(f"importing {module_name!r} failed: {error}")
    except Exception as error:
        node.fail(f"importing {module_name!r} failed: {type(error).__name__}: {error}")
    path = None if base_dir is None else base_dir / (module_name.replace(".", "/") + ".py")
    if path is None or not path.is_file():
        node.fail(
            f"cannot import {module_name!r}: not on the Python path, and no {module_name}.py beside the task file"
        )
    spec = importlib.util.spec_from_file_location(f"lerobot_contrast_task_file_{module_name}", path)
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except Exception as error:
        node.fail(f"importing {path} failed: {type(error).__name__}: {error}")
    sys.modules[spec.name] = module
    return module


def load_function(node: Node, params: dict[str, Any], base_dir: Path | None):
    """The custom perturbation function named 'module:function', checked to accept (instance, rng, **params)
    (and `task`, when it asks for the task)."""
    module_name, _, attr = node.text().partition(":")
    if not module_name or not attr:
        node.fail("expected 'module:function', e.g. my_perturbations:swap_colours")
    fn = getattr(_import(node, module_name, base_dir), attr, None)
    if not callable(fn):
        node.fail(f"module {module_name!r} has no function {attr!r}")
    try:
        inspect.signature(fn).bind(None, None, **custom_kwargs(fn, params, None))
    except TypeError as error:
        node.fail(f"{attr}() must accept (instance, rng, **params) with these params: {error}")
    return fn


def parse_perturbation(node: Node, spec: TaskSpec, base_dir: Path | None) -> PerturbationSpec:
    name = node.require("name", "the perturbation's name, e.g. LB1 (shown as ΔLB1)").text()
    description = None if node.get("description") is None else node.get("description").text()
    if node.get("function") is not None:
        node.check_keys(("name", "function", "axis", "params", "description"))
        axis = node.require("axis", f"its contrast axis, one of {', '.join(AXES)}").choice(AXES)
        params = {} if node.get("params") is None else {k: c.value for k, c in node.get("params").items()}
        fn = load_function(node.get("function"), params, base_dir)
        return PerturbationSpec(name, axis, "custom", params, description or node.get("function").value, fn)
    kind = node.require("kind", f"one of {', '.join(GENERIC)}, or `function: module:function`").choice(GENERIC)
    node.check_keys(("name", "kind", "description", *PARAMS[kind]))
    params = _params(kind, node, spec)
    reason = never_applies(kind, params, spec)
    if reason is not None:
        node.fail(f"perturbation {name!r} ({kind}) can never apply: {reason}")
    axis, _, default_description = GENERIC[kind]
    return PerturbationSpec(name, axis, kind, params, description or default_description)


def parse_perturbations(node: Node | None, spec: TaskSpec, base_dir: Path | None) -> tuple[PerturbationSpec, ...]:
    out: dict[str, PerturbationSpec] = {}
    for child in [] if node is None else node.elements():
        child.mapping()
        perturbation = parse_perturbation(child, spec, base_dir)
        if perturbation.name in out:
            child.get("name").fail(f"perturbation {perturbation.name!r} is declared twice; names must be unique")
        out[perturbation.name] = perturbation
    return tuple(out.values())
