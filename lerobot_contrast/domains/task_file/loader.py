"""Loading a task file (`--task=path/to/task.yaml`, or a shipped example by name) into a FileTask."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from lerobot_contrast.domains.task_file.nodes import Node, TaskFileError, load_yaml
from lerobot_contrast.domains.task_file.parse_perturbations import parse_perturbations
from lerobot_contrast.domains.task_file.parse_tasks import World, parse_instances, parse_outcome, parse_templates
from lerobot_contrast.domains.task_file.parse_world import NAME, UNITS, parse_cost, parse_objects, parse_workspace
from lerobot_contrast.domains.task_file.schema import VERSION, TaskSpec
from lerobot_contrast.domains.task_file.task import FileTask
from lerobot_contrast.domains.task_file.world import sample_scene

TOP_KEYS = (
    "version",
    "name",
    "description",
    "workspace",
    "objects",
    "templates",
    "instances",
    "sampler",
    "outcome",
    "perturbations",
    "cost",
)
FEASIBILITY_TRIES = 200  # draws per template at load time before it is declared impossible


def examples_dir() -> Path:
    return Path(str(resources.files("lerobot_contrast.domains.task_file") / "examples"))


def example_names() -> list[str]:
    return sorted(path.stem for path in examples_dir().glob("*.yaml"))


def task_file_path(ref: str | Path) -> Path | None:
    """The task file `ref` names: a path to a .yaml/.yml file or a shipped example's name; None otherwise."""
    text = str(ref)
    if text.endswith((".yaml", ".yml")) or "/" in text:
        path = Path(text).expanduser()
        if not path.is_file():
            raise TaskFileError(f"--task: no task file at {text}; check the path")
        return path
    if text in example_names():
        return examples_dir() / f"{text}.yaml"
    return None


def load_task_file(ref: str | Path, families: list[str] | None = None) -> FileTask:
    """Load and validate a task file by path or by a shipped example's name (e.g. "so101_blocks")."""
    path = task_file_path(ref)
    if path is None:
        raise TaskFileError(f"--task: {ref!r} is neither a task file path nor one of: {', '.join(example_names())}")
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise TaskFileError(f"{path}: cannot read the task file: {error}") from None
    return task_from_dict(load_yaml(text, str(path)), str(path), families, base_dir=path.parent)


def task_from_dict(
    data: Mapping[str, Any],
    source: str = "<task>",
    families: list[str] | None = None,
    base_dir: Path | None = None,
    default_name: str | None = None,
) -> FileTask:
    """Validate task-file data (as YAML would give it) and build the task; errors name `source` and the key."""
    root = Node(data, source, "", getattr(data, "line", None))
    root.mapping()
    root.check_keys(TOP_KEYS)
    version = root.require("version", f"the format version; this release reads version: {VERSION}")
    if version.value != VERSION:
        version.fail(f"unsupported format version {version.value!r}; this release reads version: {VERSION}")
    name = _name(root, source, default_name)
    workspace = parse_workspace(root.require("workspace", "bounds, units and named regions"))
    objects = parse_objects(root.require("objects", "the objects, by name"), workspace)
    mode, reference = parse_outcome(root.get("outcome"), UNITS[workspace.units])
    world = World(workspace, objects, mode, reference)
    templates = parse_templates(root.get("templates"), world)
    instances, seed, base_slots = _evaluation_set(root, templates, world)
    spec = TaskSpec(
        name=name,
        source=source,
        description="" if root.get("description") is None else root.get("description").text(),
        workspace=workspace,
        objects=objects,
        templates=templates,
        instances=instances,
        seed=seed,
        outcome=mode,
        perturbations=(),
        cost=parse_cost(root.get("cost"), workspace, objects),
        base_slots=base_slots,
    )
    if instances is None:
        _check_sampling(root, spec)
    spec = dataclasses.replace(spec, perturbations=parse_perturbations(root.get("perturbations"), spec, base_dir))
    return FileTask(spec, families)


def _name(root: Node, source: str, default: str | None) -> str:
    node = root.get("name")
    if node is None:
        name = default or Path(source).stem
        if not NAME.match(name):
            root.fail(f"missing key 'name': the file name {name!r} is not a usable task name; give name: my_task")
        return name
    if not NAME.match(node.text()):
        node.fail("expected an identifier (letters, digits, _), used in instance ids and run directories")
    return node.value


def _evaluation_set(root: Node, templates, world: World):
    """Listed instances (None when sampling), the sampler's seed and the slots every sampled base fixes."""
    listed, sampler = root.get("instances"), root.get("sampler")
    if listed is not None:
        if sampler is not None:
            sampler.fail("give either `instances:` (a listed evaluation set) or `sampler:`, not both")
        return parse_instances(listed, templates, world), None, {}
    if not templates:
        root.fail("missing key 'templates' (to sample instances from) or 'instances' (to list them)")
    if sampler is None:
        return None, None, {}
    sampler.check_keys(("seed", "slots"))
    seed = sampler.get("seed")
    return None, None if seed is None else seed.integer(minimum=0), _base_slots(sampler.get("slots"), templates)


def _base_slots(node: Node | None, templates) -> dict[str, str]:
    """sampler.slots: the value each named slot takes in every sampled base (perturbations may still change it)."""
    if node is None:
        return {}
    fixed = {name: child.text() for name, child in node.items()}
    for name, child in node.items():
        allowed = sorted({c for t in templates.values() if name in t.slots for c in t.slots[name].candidates})
        if not allowed:
            child.fail(
                f"no template has a slot {name!r}; slots: {', '.join(sorted({s for t in templates.values() for s in t.slots}))}"
            )
        if fixed[name] not in allowed:
            child.fail(f"{fixed[name]!r} is not allowed in slot {name!r}; expected one of: {', '.join(allowed)}")
    if not any(template.takes(fixed) for template in templates.values()):
        node.fail("no single template has all these slots with these values; fix fewer slots")
    return fixed


def _check_sampling(root: Node, spec: TaskSpec) -> None:
    """Objects fit in their areas, and every template yields a valid instance that is not already achieved."""
    rng = np.random.default_rng(0)
    if sample_scene(spec, rng) is None:
        workspace = root.get("workspace")
        spacing = spec.workspace.min_spacing / UNITS[spec.workspace.units]
        (workspace.get("min_spacing") or workspace).fail(
            f"cannot place the {len(spec.placed)} movable objects {spacing:g} {spec.workspace.units} apart in their "
            "areas; lower min_spacing, widen the areas, or mark some objects spare"
        )
    task = FileTask(spec)
    for node, template in zip(root.get("templates").elements(), spec.templates.values(), strict=True):
        if spec.fits_bases(template) and not any(
            task.try_template(template, "check", rng) for _ in range(FEASIBILITY_TRIES)
        ):
            node.fail(
                f"template {template.key!r} never gives a valid instance: its goal already holds in every sampled "
                "scene, or a slot has no candidate present; check the goal and the objects' areas"
            )
