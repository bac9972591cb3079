"""Every policy comes from one registry: scripted baselines say their task, and a LeRobot checkpoint is one entry."""

import numpy as np
import pytest

from lerobot_contrast import PolicyArgs, TrialContext, load_task, make_policy
from lerobot_contrast.domains.language_table.config_language_table_sim import LanguageTableSimConfig
from lerobot_contrast.domains.language_table.language_table_sim import LanguageTableSim
from lerobot_contrast.policies import (
    DEFAULT_POLICY,
    LEROBOT,
    POLICIES,
    PRETRAINED_BUILD,
    PolicyEntry,
    PolicyError,
    policy_entry,
)
from lerobot_contrast.policies.pretrained import PretrainedPolicy
from tests.lerobot_helpers import save_act


def test_scripted_baselines_are_registered_with_the_task_they_solve():
    scripted = ("oracle", "random", "route_follower")
    assert {name: POLICIES[name].task for name in scripted} == {
        "oracle": "language_table",
        "random": None,
        "route_follower": "vln",
    }
    assert policy_entry(PolicyArgs()) is POLICIES[DEFAULT_POLICY]
    assert policy_entry(PolicyArgs(type="oracle")).name == "oracle"
    assert policy_entry(PolicyArgs(path="user/model")) is LEROBOT
    assert policy_entry(PolicyArgs(type="act")) is LEROBOT  # a LeRobot policy type, built fresh


def test_a_policy_that_does_not_fit_the_task_is_refused_in_one_line():
    robot = LanguageTableSim(LanguageTableSimConfig())
    with pytest.raises(PolicyError, match="--policy.type=route_follower navigates --task=vln"):
        make_policy(PolicyArgs(type="route_follower"), robot, load_task("language_table"))


def test_a_registered_checkpoint_loads_as_a_lerobot_policy(tmp_path, monkeypatch):
    path = save_act(tmp_path / "model")
    entry = PolicyEntry(
        "shipped_act", PRETRAINED_BUILD, "an ACT shipped as a directory", reads_images=True, path=str(path)
    )
    monkeypatch.setitem(POLICIES, entry.name, entry)
    robot = LanguageTableSim(LanguageTableSimConfig())
    policy = make_policy(PolicyArgs(type="shipped_act", device="cpu"), robot, load_task("language_table"))
    assert isinstance(policy, PretrainedPolicy) and policy.name == "act"
    robot.connect()
    try:
        task = load_task("language_table")
        instance = task.sample(1, np.random.default_rng(0))[0]
        robot.stage_scene(instance.scene)
        context = TrialContext(0, instance, instance, instance.scene, 0.0, "reset", np.random.default_rng(0), 1)
        policy.reset(context)
        assert set(policy.act(robot.get_observation())) == {"delta_x", "delta_y"}
    finally:
        robot.disconnect()


def test_noise_std_makes_a_noisier_copy_of_the_learned_default_drawn_from_the_trial():
    import lerobot_policy_tabletop_pointer  # noqa: F401  registers the policy type, as eval's plugin discovery does

    robot = LanguageTableSim(LanguageTableSimConfig())
    task = load_task("language_table")
    plain = make_policy(PolicyArgs(), robot, task)
    noisy = make_policy(PolicyArgs(noise_std=0.02), robot, task)
    robot.connect()
    try:
        instance = task.sample(1, np.random.default_rng(0))[0]
        robot.stage_scene(instance.scene)
        observation = robot.get_observation()

        def act(policy, seed):
            context = TrialContext(0, instance, instance, instance.scene, 0.0, "reset", np.random.default_rng(seed), 1)
            policy.reset(context)
            return np.array(list(policy.act(observation).values()))

        clean = act(plain, 0)
        first, again, other = act(noisy, 0), act(noisy, 0), act(noisy, 1)
    finally:
        robot.disconnect()
    assert noisy.name == plain.name == "tabletop_pointer"
    assert np.array_equal(first, again)  # the trial's own randomness: a resumed trial draws the same noise
    assert not np.allclose(first, clean) and not np.allclose(first, other)
    assert np.all(np.abs(first - clean) < 0.1)


def test_noise_std_on_a_policy_without_continuous_actions_is_refused_in_one_line():
    robot = LanguageTableSim(LanguageTableSimConfig())
    with pytest.raises(PolicyError, match="--policy.type=random takes no action noise"):
        make_policy(PolicyArgs(type="random", noise_std=0.01), robot, load_task("language_table"))


def test_a_policy_whose_distribution_is_not_installed_is_named_in_one_line(monkeypatch):
    entry = PolicyEntry("elsewhere", "lerobot_policy_not_installed.policy:build", "a plugin's policy")
    monkeypatch.setitem(POLICIES, entry.name, entry)
    robot = LanguageTableSim(LanguageTableSimConfig())
    with pytest.raises(PolicyError, match=r"^--policy.type=elsewhere needs the lerobot_policy_not_installed "
                                          r"distribution, which is not installed: pip install "):  # fmt: skip
        make_policy(PolicyArgs(type="elsewhere"), robot, load_task("language_table"))


def test_an_option_a_policy_does_not_take_is_refused_in_one_line():
    robot = LanguageTableSim(LanguageTableSimConfig())
    task = load_task("language_table")
    with pytest.raises(PolicyError, match=r"^--policy.options: oracle has no option placement; it takes none$"):
        make_policy(PolicyArgs(type="oracle", options={"placement": "tcp://127.0.0.1:5556"}), robot, task)
    assert POLICIES["so101_demonstrator"].options == ("placement",)


def test_policy_options_parse_from_the_command_line():
    from lerobot_contrast.spine.config import EvalConfig
    from lerobot_contrast.spine.flags import parse_config

    config = parse_config(
        EvalConfig, ["--policy.type=so101_demonstrator", "--policy.options={placement: tcp://127.0.0.1:5557}"]
    )
    assert config.policy.options == {"placement": "tcp://127.0.0.1:5557"}
