"""Evaluation strategies: turn an evaluation set into an ordered sequence of planned trials.

A planned trial names its base instance, the perturbation to apply (None for the instruction as
sampled) and how its scene is staged. The concrete instance is only known at run time, because
perturbations act on the scene the robot left behind (see `staging.materialize`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np

from lerobot_contrast.contrast.cost import CostModel
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.perturbation import Perturbation
from lerobot_contrast.contrast.schedule import cost_aware_order

# reset: stage the instance's own scene. in_place: perturb the scene the robot left behind.
# in_place_or_reset: give the instruction in the current scene, resetting only where it is infeasible.
Staging = Literal["reset", "in_place", "in_place_or_reset"]


@dataclass(frozen=True)
class PlannedTrial:
    index: int
    base: Instance
    perturbation: str | None
    staging: Staging
    repeat: int = 0

    def to_json(self) -> dict[str, Any]:
        return {
            "index": self.index,
            "base_id": self.base.id,
            "perturbation": self.perturbation,
            "staging": self.staging,
            "repeat": self.repeat,
        }


def _expand(steps: list[tuple[Instance, str | None, Staging]], repeats: int) -> list[PlannedTrial]:
    if repeats < 1:
        raise UserError(f"--repeats must be at least 1, got {repeats}")
    trials: list[PlannedTrial] = []
    for base, perturbation, staging in steps:
        for repeat in range(repeats):
            trials.append(PlannedTrial(len(trials), base, perturbation, staging, repeat))
    return trials


def plan_standard(
    instances: list[Instance], perturbations: list[Perturbation], repeats: int, rng: np.random.Generator
) -> list[PlannedTrial]:
    """i.i.d. order; every trial restages its own scene from wherever the previous one left it."""
    order = rng.permutation(len(instances))
    return _expand([(instances[i], None, "reset") for i in order], repeats)


def plan_contrast(
    instances: list[Instance], perturbations: list[Perturbation], repeats: int, rng: np.random.Generator
) -> list[PlannedTrial]:
    """Algorithm 1: each base instance, then each perturbation of it in sequence without resetting."""
    steps: list[tuple[Instance, str | None, Staging]] = []
    for base in instances:
        steps.append((base, None, "reset"))
        steps.extend((base, p.name, "in_place") for p in perturbations)
    return _expand(steps, repeats)


def plan_limited_intervention(
    instances: list[Instance], perturbations: list[Perturbation], repeats: int, rng: np.random.Generator
) -> list[PlannedTrial]:
    """New instructions from the evaluation set in the current scene; reset only where infeasible."""
    return _expand([(base, None, "in_place_or_reset") for base in instances], repeats)


STRATEGIES = {
    "standard": plan_standard,
    "contrast": plan_contrast,
    "limited_intervention": plan_limited_intervention,
}


# How base instances are visited: "iid" keeps the sampled order; "cost_aware" reorders the bases, each with
# its chain of trials, to cut staging cost (see schedule.py); "adaptive" keeps the sampled order and plans as
# "iid", and the run chooses each next trial from the outcomes so far (see adaptive.py).
ORDERS = ("iid", "cost_aware", "adaptive")


def make_plan(
    strategy: str,
    instances: list[Instance],
    perturbations: list[Perturbation],
    repeats: int,
    rng: np.random.Generator,
    order: str = "iid",
    cost: CostModel | None = None,
) -> list[PlannedTrial]:
    """The planned trials of `strategy`; `cost` (the run's cost model; default: distance) prices cost_aware order."""
    try:
        planner = STRATEGIES[strategy]
    except KeyError:
        raise UserError(f"--strategy: unknown strategy {strategy!r}; choose from: {', '.join(STRATEGIES)}") from None
    if order not in ORDERS:
        raise UserError(f"--order: unknown order {order!r}; choose from: {', '.join(ORDERS)}")
    plan = planner(instances, perturbations, repeats, rng)
    return reorder_plan(plan, cost) if order == "cost_aware" else plan


def reorder_plan(plan: list[PlannedTrial], cost: CostModel | None = None) -> list[PlannedTrial]:
    """The same trials, with each base's chain kept together and the chains in cost-aware order.

    Deterministic: the order depends only on the plan (itself seeded), and ties go to the earlier base.
    """
    chains: dict[str, list[PlannedTrial]] = {}
    for trial in plan:
        chains.setdefault(trial.base.id, []).append(trial)
    firsts = [chain[0].base for chain in chains.values()]
    ordered = [trial for k in cost_aware_order(firsts, cost) for trial in chains[firsts[k].id]]
    return [replace(trial, index=index) for index, trial in enumerate(ordered)]


def exceeds_budget(cumulative_cost: float, budget: float | None) -> bool:
    """Algorithm 1's stopping rule: stop once the cumulative cost exceeds the budget K.

    The trial whose staging crosses K is still run and counted, exactly as in the paper.
    """
    return budget is not None and cumulative_cost > budget
