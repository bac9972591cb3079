"""Perturbations: named functions Instance -> Instance | None along one of the four contrast axes."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Literal

import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.instance import Instance

Axis = Literal["L", "LB", "S", "SB"]
AXES: tuple[Axis, ...] = ("L", "LB", "S", "SB")

PerturbFn = Callable[[Instance, np.random.Generator], "Instance | None"]


@dataclass(frozen=True)
class Perturbation:
    """A named perturbation on one axis.

    `apply` receives the instance to perturb, set in the scene the robot currently faces, and
    returns the perturbed instance or None where the perturbation does not apply there.
    Language axes (L, LB) must leave the scene untouched, so they cost nothing to stage.
    """

    name: str
    axis: Axis
    apply: PerturbFn
    description: str = ""

    def __post_init__(self) -> None:
        if self.axis not in AXES:
            raise ValueError(f"perturbation {self.name!r}: axis must be one of {AXES}, got {self.axis!r}")

    @property
    def label(self) -> str:
        return perturbation_label(self.name)


def perturbation_label(name: str | None) -> str:
    """The paper's notation, e.g. ΔLB1; "original" for an unperturbed instance."""
    return "original" if name is None else f"Δ{name}"


class UnknownPerturbationError(UserError):
    pass


class PerturbationRegistry:
    """Perturbations by name, in registration order."""

    def __init__(self, owner: str) -> None:
        self.owner = owner
        self._items: dict[str, Perturbation] = {}

    def register(self, name: str, axis: Axis, description: str = "") -> Callable[[PerturbFn], PerturbFn]:
        def decorator(fn: PerturbFn) -> PerturbFn:
            self.add(Perturbation(name=name, axis=axis, apply=fn, description=description))
            return fn

        return decorator

    def add(self, perturbation: Perturbation) -> None:
        if perturbation.name in self._items:
            raise ValueError(f"{self.owner}: perturbation {perturbation.name!r} is registered twice")
        self._items[perturbation.name] = perturbation

    def get(self, name: str) -> Perturbation:
        try:
            return self._items[name]
        except KeyError:
            known = ", ".join(self._items) or "none"
            raise UnknownPerturbationError(
                f"unknown perturbation {name!r} for task {self.owner!r}; choose from: {known}"
            ) from None

    def select(self, names: list[str] | tuple[str, ...] | None) -> list[Perturbation]:
        """The named perturbations in the given order; all of them when `names` is None."""
        if names is None:
            return list(self._items.values())
        try:
            return [self.get(name) for name in names]
        except UnknownPerturbationError as error:
            raise UnknownPerturbationError(f"--perturbations: {error}") from None

    def __iter__(self) -> Iterator[Perturbation]:
        return iter(self._items.values())

    def __contains__(self, name: object) -> bool:
        return name in self._items

    def __len__(self) -> int:
        return len(self._items)
