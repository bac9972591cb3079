"""PushOracle solves every family within the episode limit; reference_path gives SPL its reference length."""

import numpy as np
import pytest

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.domains.language_table import FAMILIES, LanguageTableTask
from lerobot_contrast.domains.language_table.env import LanguageTableEnv
from lerobot_contrast.domains.language_table.oracle import PushOracle, plan_path, reference_path

TASK = LanguageTableTask()


def instances(family: str, n: int, seed: int) -> list[Instance]:
    return LanguageTableTask(families=(family,)).sample(n, np.random.default_rng(seed))


def solve(env: LanguageTableEnv, oracle: PushOracle, instance: Instance) -> int | None:
    """Steps the oracle needs, or None when it fails within the episode limit."""
    obs, info = env.reset(options={"instance": instance})
    oracle.reset(instance)
    for step in range(env._max_episode_steps):
        obs, _, terminated, _, info = env.step(oracle.act(env.scene(), obs["effector_target_translation"]))
        if terminated:
            return step + 1
    return None


@pytest.mark.parametrize("family", FAMILIES)
def test_oracle_solves_a_few_instances(family):
    env, oracle = LanguageTableEnv(obs_type="state"), PushOracle(TASK)
    assert all(solve(env, oracle, instance) for instance in instances(family, 2, seed=11))


@pytest.mark.slow
@pytest.mark.parametrize("family", FAMILIES)
def test_oracle_success_rate_per_family(family):
    env, oracle = LanguageTableEnv(obs_type="state"), PushOracle(TASK)
    steps = [solve(env, oracle, instance) for instance in instances(family, 40, seed=2024)]
    assert np.mean([s is not None for s in steps]) >= 0.9


def test_noise_comes_from_the_oracles_own_rng():
    instance = instances("block2block", 1, seed=5)[0]
    actions = []
    for _ in range(2):
        oracle = PushOracle(TASK, noise_std=0.01, rng=np.random.default_rng(7))
        oracle.reset(instance)
        actions.append(oracle.act(instance.scene, (instance.scene.robot.x, instance.scene.robot.y)))
    quiet = PushOracle(TASK)
    quiet.reset(instance)
    clean = quiet.act(instance.scene, (instance.scene.robot.x, instance.scene.robot.y))
    assert np.array_equal(actions[0], actions[1]) and not np.array_equal(actions[0], clean)
    assert actions[0].dtype == np.float32 and actions[0].shape == (2,)


def test_plan_path_goes_around_a_block():
    start, goal, block = np.array((0.3, 0.0)), np.array((0.5, 0.0)), np.array([(0.4, 0.0)])
    path = plan_path(start, goal, block, 0.05)
    assert len(path) > 2
    assert (path[0] == start).all() and (path[-1] == goal).all()
    assert min(np.linalg.norm(p - block[0]) for p in path[1:-1]) >= 0.05


def test_reference_path_of_a_solved_instance():
    instance = instances("block2relativelocation", 1, seed=3)[0]
    reference = reference_path(TASK, instance)
    assert reference.success and 0 < reference.steps < 200
    assert reference.length_m > 0.02


def test_reference_path_falls_back_to_a_straight_line_estimate():
    instance = instances("block2absolutelocation", 1, seed=3)[0]
    reference = reference_path(TASK, instance, max_steps=1)
    assert not reference.success
    assert reference.length_m > 0
