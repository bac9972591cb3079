"""FileTask: a task declared in a task file, as a contrast-set Task with the optional outcome hooks."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from lerobot_contrast.contrast.cost import CostModel
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.perturbation import Perturbation, PerturbationRegistry, PerturbFn
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.contrast.task import Task
from lerobot_contrast.domains.task_file import cost, goals, perturbations, world
from lerobot_contrast.domains.task_file.schema import PerturbationSpec, TaskSpec, Template
from lerobot_contrast.domains.task_file.wording import pick

SAMPLE_TRIES = 1000  # scene and slot draws per instance before the sampler gives up


class FileTask(Task):
    """The task a task file declares: samples or lists instances, grounds and judges them, and registers the
    file's perturbations. Use `load_task_file` (a path or a shipped example's name) or `task_from_dict`."""

    def __init__(self, spec: TaskSpec, families: list[str] | None = None) -> None:
        self.spec = spec
        self.name = spec.name
        self.outcome = spec.outcome
        listed = () if spec.instances is None else spec.instances
        self.templates = {**spec.templates, **{item.template.key: item.template for item in listed}}
        known = sorted({t.family for t in self._in_use()})
        unknown = [f for f in families or () if f not in known]
        if unknown:
            raise UserError(
                f"--families: unknown families {unknown} for task {self.name!r}; choose from: {', '.join(known)}"
            )
        self.families = tuple(families or known)
        self.perturbations = PerturbationRegistry(self.name)
        for p in spec.perturbations:
            self.perturbations.add(Perturbation(p.name, p.axis, self._perturb_fn(p), p.description))

    def _in_use(self) -> list[Template]:
        if self.spec.instances is not None:
            return [item.template for item in self.spec.instances]
        return list(self.spec.templates.values())

    def _perturb_fn(self, p: PerturbationSpec) -> PerturbFn:
        if p.function is None:
            return perturbations.build(self, p.kind, dict(p.params))
        fn, kwargs = p.function, perturbations.custom_kwargs(p.function, p.params, self)
        return lambda instance, rng: fn(instance, rng, **kwargs)

    # --- building instances ---

    def make_instance(
        self, id: str, template: str | Template, slots: Mapping[str, str], scene: Scene, words=None, text=None
    ) -> Instance:
        """An instance of `template` with `slots` filled, set in `scene` (plain wording unless given)."""
        if isinstance(template, str):
            if template not in self.templates:
                raise UserError(f"task {self.name!r} has no template {template!r}; it has: {', '.join(self.templates)}")
            template = self.templates[template]
        for name, slot in template.slots.items():
            if slots.get(name) not in slot.candidates:
                raise UserError(
                    f"template {template.key!r}: slot {name!r} needs one of {', '.join(slot.candidates)}, "
                    f"got {slots.get(name)!r}"
                )
        words = {s: self.spec.words(v)[0] for s, v in slots.items()} | dict(words or {})
        instruction, goal = goals.compose(template, text or template.texts[0], slots, words)
        return Instance(id, template.family, instruction, scene, goal)

    def template_of(self, instance: Instance) -> Template:
        return self.templates[instance.goal["template"]]

    def compose(self, instance: Instance, *, slots=None, words=None, text=None) -> Instance:
        """`instance` with some slots, words or its template text changed, instruction and goal re-rendered.

        A changed slot without a given word is said with its new referent's plain word."""
        goal = instance.goal
        new_slots = {**goal["slots"], **(slots or {})}
        new_words = {}
        for name, value in new_slots.items():
            if words and name in words:
                new_words[name] = words[name]
            else:
                new_words[name] = goal["words"][name] if value == goal["slots"][name] else self.spec.words(value)[0]
        instruction, new_goal = goals.compose(self.template_of(instance), text or goal["text"], new_slots, new_words)
        return instance.derive(instruction=instruction, goal=new_goal)

    @property
    def default_instances(self) -> int:
        """Without --n_instances: every listed instance, or 50 sampled ones."""
        if self.spec.instances is None:
            return 50
        return sum(item.template.family in self.families for item in self.spec.instances)

    # --- the Task protocol ---

    def sample(self, n: int, rng: np.random.Generator) -> list[Instance]:
        """`n` instances: the first `n` listed ones, or `n` drawn from the templates (with the file's seed if set)."""
        if self.spec.instances is not None:
            listed = [(k, item) for k, item in enumerate(self.spec.instances) if item.template.family in self.families]
            if n > len(listed):
                which = " of these families" if len(listed) < len(self.spec.instances) else ""
                raise UserError(
                    f"--n_instances={n}: {self.spec.source} lists {len(listed)} instances{which}; "
                    f"ask for at most {len(listed)}"
                )
            return [self._listed(k, item) for k, item in listed[:n]]
        if self.spec.seed is not None:
            rng = np.random.default_rng(self.spec.seed)
        return [self._sample_one(f"{self.name}-{k:04d}", rng) for k in range(n)]

    def _listed(self, k: int, item) -> Instance:
        return self.make_instance(
            f"{self.name}-{k:04d}", item.template, item.slots, world.listed_scene(item, self.spec.objects)
        )

    def _sample_one(self, id: str, rng: np.random.Generator) -> Instance:
        templates = [t for t in self.spec.templates.values() if t.family in self.families and self.spec.fits_bases(t)]
        if not templates:
            raise UserError(
                f"--families: no template of {', '.join(self.families)} gives the bases {self.spec.source}'s "
                "sampler.slots fixes; choose other families"
            )
        weights = np.array([t.weight for t in templates])
        for _ in range(SAMPLE_TRIES):
            template = templates[int(rng.choice(len(templates), p=weights / weights.sum()))]
            instance = self.try_template(template, id, rng)
            if instance is not None:
                return instance
        raise UserError(
            f"{self.spec.source}: could not sample a valid instance in {SAMPLE_TRIES} tries; widen the areas"
        )

    def try_template(self, template: Template, id: str, rng: np.random.Generator) -> Instance | None:
        """One draw of scene and slots for `template`; None when they give no valid, not yet achieved goal."""
        scene = world.sample_scene(self.spec, rng)
        if scene is None:
            return None
        slots, used = {}, set()
        for name, slot in template.slots.items():
            options = [c for c in slot.candidates if c not in used and (slot.kind == "region" or c in scene.objects)]
            if name in self.spec.base_slots:
                options = [c for c in options if c == self.spec.base_slots[name]]
            if not options:
                return None
            slots[name] = pick(rng, options)
            used.add(slots[name])
        instance = self.make_instance(id, template, slots, scene)
        return None if self.is_achieved(instance, scene) else instance

    def storage_scene(self) -> Scene:
        return world.storage_scene(self.spec)

    def rebase(self, instance: Instance, scene: Scene) -> Instance | None:
        if any(name not in scene.objects for name in goals.involved(instance.goal, self.spec.objects)):
            return None
        return instance.derive(scene=scene)

    def is_achieved(self, instance: Instance, scene: Scene) -> bool:
        return goals.holds(instance.goal.get("predicate"), scene, self.spec.workspace.regions)

    # --- optional hooks ---

    def subgoals(self, instance: Instance) -> list[str]:
        return list(instance.goal.get("subgoals", ()))

    def reference_length(self, instance: Instance) -> float | None:
        """Metres of the reference path for SPL: declared, or straight lines robot -> object -> goal."""
        reference = self.template_of(instance).reference
        if reference == "straight_line":
            return goals.straight_line(instance.goal, instance.scene, self.spec.workspace.regions)
        return reference

    def cost_model(self, name: str) -> CostModel:
        """The `--cost` model (`distance` or `reset_time`) with this file's tolerance, charges and handling times."""
        return cost.make_cost_model(self.spec.cost, name)
