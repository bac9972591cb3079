"""Plans on all four suites without a simulator: instances come from LIBERO's init states, and each perturbation
changes what it declares and nothing else, or says it does not apply."""

from __future__ import annotations

import numpy as np
import pytest

from lerobot_contrast import load_task
from lerobot_contrast.contrast.task import perturb
from lerobot_contrast.domains.libero import goals

pytest.importorskip("libero", reason="LIBERO is installed by the test set-up: bash scripts/setup.sh --dev")
pytestmark = pytest.mark.slow


@pytest.mark.parametrize("suite", ["libero_spatial", "libero_object", "libero_goal", "libero_10"])
def test_each_perturbation_changes_what_it_declares(suite):
    task = load_task(suite)
    rng = np.random.default_rng(0)
    applied = set()
    for instance in task.sample(12, rng):
        assert instance.family.startswith("task") and len(instance.scene.objects) >= 2
        named = goals.named(goals.goal_of(instance.goal), list(instance.scene.objects))
        for perturbation in task.perturbations:
            out = perturb(task, perturbation, instance, rng)
            if out is None:
                continue
            applied.add(perturbation.name)
            moved = {n for n, p in out.scene.objects.items() if p != instance.scene.objects[n]}
            if perturbation.axis in ("L", "LB"):
                assert not moved and out.instruction != instance.instruction
                assert (out.goal == instance.goal) == (perturbation.axis == "L")
            else:
                (name,) = moved
                assert 0.05 <= instance.scene.objects[name].distance_to(out.scene.objects[name]) <= 0.10 + 1e-9
                assert (name in named) == (perturbation.axis == "SB")
                assert out.instruction == instance.instruction and out.goal == instance.goal
    assert applied == {"L", "LB", "S", "SB"}


def test_going_to_another_libero_world_pays_for_clearing_the_table_and_setting_the_new_one():
    task = load_task("libero_object")
    a, b = task.instance(0, 0), task.instance(1, 0)
    storage, cost = task.storage_scene(), task.cost_model("distance")
    leaving, arriving = set(a.scene.objects) - set(b.scene.objects), set(b.scene.objects) - set(a.scene.objects)
    assert leaving and arriving
    carried = sum(a.scene.objects[n].distance_to(storage.objects[n]) for n in leaving)
    carried += sum(storage.objects[n].distance_to(b.scene.objects[n]) for n in arriving)
    assert cost(a.scene, b.scene) >= carried > 0.5
    assert cost(a.scene, a.scene) == 0.0
