"""`--env.type=language_table`: the tabletop simulator as a LeRobot env, with the keys, fps, success signal and
instances LeRobot's tools and our evaluator share."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from lerobot.envs.configs import EnvConfig
from lerobot.envs.utils import env_to_policy_features, preprocess_observation
from lerobot.utils.import_utils import register_third_party_plugins
from lerobot_policy_tabletop_pointer import WEIGHTS

from lerobot_contrast import load_task, make_plan, stats
from lerobot_contrast.domains.language_table.oracle import PushOracle
from lerobot_contrast.domains.language_table.task import LanguageTableTask
from lerobot_contrast.record.plan_file import write_plan
from lerobot_contrast.training.episodes import NoisyOracle, Simulator, open_dataset, record_episodes

BIN = Path(sys.executable).parent


def env_config(**fields):
    register_third_party_plugins()  # as every lerobot-* command does: finds the plugin by its distribution name
    return EnvConfig.get_choice_class("language_table")(**fields)


def one_env(**fields):
    (group,) = env_config(**fields).create_envs(1).values()
    return group[0]


def write_run_plan(run_dir: Path, n: int, seed: int = 0) -> list:
    task = load_task("language_table")
    rng = np.random.default_rng(seed)
    plan = make_plan("standard", task.sample(n, rng), [], repeats=1, rng=rng)
    write_plan(run_dir, plan)
    return [trial.base for trial in plan]


def test_the_env_gives_what_the_shipped_policy_reads():
    config = env_config()
    policy = json.loads((WEIGHTS / "config.json").read_text())["input_features"]
    features = env_to_policy_features(config)
    shapes = {key: list(feature.shape) for key, feature in features.items() if key != "action"}
    assert shapes == {key: feature["shape"] for key, feature in policy.items()}
    assert config.fps == 10 and features["action"].shape == (2,)
    env = one_env()
    observation, info = env.reset(seed=[5])
    assert observation["pixels"]["top"].shape == (1, 180, 320, 3) and observation["pixels"]["top"].dtype == np.uint8
    assert set(preprocess_observation(observation)) == {"observation.images.top", "observation.state"}
    assert env.call("_max_episode_steps") == (200,) and env.call("task_description")[0].startswith(("push", "move"))
    effector = env.call("unwrapped")[0].physics.effector
    np.testing.assert_allclose(observation["agent_pos"][0, :2], effector, atol=1e-6)
    assert info["is_success"].tolist() == [False]


def test_is_success_comes_when_the_oracle_has_pushed_the_block_home():
    env = one_env()
    observation, _ = env.reset(seed=[1])
    sim = env.call("unwrapped")[0]
    oracle = PushOracle(sim.task_model)
    oracle.reset(sim.instance)
    steps, terminated = 0, [False]
    while not terminated[0] and steps < 200:
        action = oracle.act(sim.scene(), observation["agent_pos"][0, 2:])
        observation, reward, terminated, _, info = env.step(action[None])
        steps += 1
    # The vector env resets a finished board at once; the finished episode's info is its `final_info`, as LeRobot reads.
    assert steps < 200 and info["final_info"]["is_success"].tolist() == [True] and reward.tolist() == [1.0]


def test_each_named_family_is_its_own_task_group():
    envs = env_config(task="block2block, separate").create_envs(1)
    assert set(envs) == {"block2block", "separate"}
    for family, group in envs.items():
        group[0].reset(seed=[0])
        assert group[0].call("unwrapped")[0].instance.family == family


def test_with_a_run_directory_the_episodes_play_its_instances_in_order(tmp_path):
    bases = write_run_plan(tmp_path, 3)
    env = one_env(instances=str(tmp_path))
    for seed, expected in [(0, bases[0]), (2, bases[2]), (3, bases[0])]:
        env.reset(seed=[seed])
        sim = env.call("unwrapped")[0]
        assert sim.instance.id == expected.id and sim.task_description == expected.instruction
        played, planned = sim.scene().objects, expected.scene.objects
        assert set(played) == set(planned)
        np.testing.assert_allclose(
            [(played[n].x, played[n].y) for n in planned], [(p.x, p.y) for p in planned.values()], atol=1e-6
        )


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"task": "block2nowhere"}, "--env.task: unknown Language-Table families block2nowhere; give all or some of"),
        ({"episode_length": 0}, "--env.episode_length must be a whole number >= 1, got 0"),
        ({"instances": "no/such/run"}, "--env.instances: no/such/run does not exist; give a run directory"),
    ],
)
def test_a_bad_env_flag_is_refused_in_one_line(fields, message):
    with pytest.raises(SystemExit) as refused:
        env_config(**fields).create_envs(1)
    assert str(refused.value.code).startswith(message) and "\n" not in str(refused.value.code)


def test_lerobot_eval_refuses_a_bad_family_in_one_line():
    flags = ["--env.type=language_table", "--env.task=block2nowhere", f"--policy.path={WEIGHTS}"]
    done = subprocess.run([BIN / "lerobot-eval", *flags], capture_output=True, text=True, timeout=300)
    assert done.returncode != 0 and "Traceback" not in done.stderr
    assert done.stderr.strip().splitlines()[-1].startswith("--env.task: unknown Language-Table families block2nowhere")


@pytest.mark.slow
def test_lerobot_eval_and_our_standard_evaluation_agree_on_the_same_instances(tmp_path):
    n = 12
    ours = tmp_path / "ours"
    evaluate = [sys.executable, "-m", "lerobot_contrast.eval", "--strategy=standard", f"--n_instances={n}", "--seed=3"]
    subprocess.run([*evaluate, "--rerun=false", f"--output_dir={ours}"], check=True, capture_output=True, timeout=1800)
    lerobot_eval = [
        BIN / "lerobot-eval", "--env.type=language_table", f"--env.instances={ours}", f"--policy.path={WEIGHTS}",
        "--policy.device=cpu", f"--eval.n_episodes={n}", "--eval.batch_size=1", "--seed=0",
        f"--output_dir={tmp_path / 'lerobot'}",
    ]  # fmt: skip
    subprocess.run(lerobot_eval, check=True, capture_output=True, timeout=1800)
    info = json.loads((tmp_path / "lerobot" / "eval_info.json").read_text())
    theirs = info["per_task"][0]["metrics"]["successes"]
    results = stats.frame(pq.read_table(ours / "results.parquet"))
    ours_estimate = stats.metric_estimate(results, "success")
    rate = info["overall"]["pc_success"] / 100
    assert len(theirs) == n and rate == pytest.approx(np.mean(theirs))
    assert ours_estimate.n_trials == n and ours_estimate.low <= rate <= ours_estimate.high, (rate, ours_estimate)
    # Episode k played the run's k-th instance in the same physics with the same policy: nearly every outcome matches.
    played = json.loads((ours / "plan.json").read_text())["trials"]
    ours_by_instance = dict(zip(results.instance_id, results.success, strict=True))
    same = [ours_by_instance[trial["base"]["id"]] == success for trial, success in zip(played, theirs, strict=True)]
    assert np.mean(same) >= 0.8, same


@pytest.mark.slow
def test_lerobot_train_evaluates_on_the_env_while_it_trains(tmp_path):
    task, rng = LanguageTableTask(), np.random.default_rng(0)
    dataset = open_dataset(tmp_path / "demos", "local/lt_demos")  # the learned default's kind of training data
    record_episodes(dataset, Simulator(task), task.sample(2, rng), NoisyOracle(0.0, rng), 20)
    dataset.finalize()
    lerobot_train = [
        BIN / "lerobot-train", "--dataset.repo_id=local/lt_demos", f"--dataset.root={tmp_path / 'demos'}",
        "--policy.type=tabletop_pointer", "--policy.push_to_hub=false", "--policy.device=cpu", "--steps=2",
        "--batch_size=2", "--save_freq=2", "--env_eval_freq=2", "--env.type=language_table", "--env.episode_length=10",
        "--eval.n_episodes=1", "--eval.batch_size=1", "--num_workers=0", f"--output_dir={tmp_path / 'train'}",
        "--wandb.enable=false",
    ]  # fmt: skip
    done = subprocess.run(
        lerobot_train, capture_output=True, text=True, timeout=1800, env={**os.environ, "HF_HUB_OFFLINE": "1"}
    )
    assert done.returncode == 0, done.stderr[-3000:]
    logged = done.stdout + done.stderr  # the eval's aggregated metrics, as lerobot-train logs them
    assert "'task_group': 'language_table'" in logged and "'n_episodes': 1" in logged
    assert list((tmp_path / "train" / "eval" / "videos_step_000002" / "language_table_0").glob("*.mp4"))
