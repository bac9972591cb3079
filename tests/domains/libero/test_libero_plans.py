"""Plans on all four suites without a simulator: instances come from LIBERO's init states, and each perturbation
changes what it declares and nothing else, or says it does not apply."""

from __future__ import annotations

import numpy as np
import pytest

from lerobot_contrast import load_task
from lerobot_contrast.contrast.task import perturb
from lerobot_contrast.domains.libero import goals

pytest.importorskip("libero", reason="LIBERO is installed by the test set-up: bash scripts/setup.sh --libero")
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
