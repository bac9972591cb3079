"""Which simulators hold which scene, so that a staged scene is judged by LIBERO's own predicates (`check_success`
parts) in the simulator that holds it, while the task and the runner keep passing plain Scenes."""

from __future__ import annotations

import weakref
from collections.abc import Sequence
from typing import Protocol

from lerobot_contrast.contrast.scene import Scene

# A scene is the simulator's own when every object is within this distance of where the simulator has it (metres).
SAME_M = 1e-4


class Judge(Protocol):
    def read_scene(self) -> Scene: ...

    def goal_holds(self, goal: Sequence[Sequence[str]]) -> bool: ...


_LIVE: weakref.WeakSet = weakref.WeakSet()


def attach(simulator: Judge) -> None:
    _LIVE.add(simulator)


def detach(simulator: Judge) -> None:
    _LIVE.discard(simulator)


def holds(goal: Sequence[Sequence[str]], scene: Scene) -> bool | None:
    """LIBERO's verdict from a live simulator holding `scene`; None when no simulator holds it."""
    for simulator in list(_LIVE):
        current = simulator.read_scene()
        if current.objects.keys() == scene.objects.keys() and all(
            current.objects[name].distance_to(pose) <= SAME_M for name, pose in scene.objects.items()
        ):
            return simulator.goal_holds(goal)
    return None
