"""Any LeRobot policy through --policy.path: loading, the instruction as `task`, language-blindness under ΔL."""

import json
import subprocess
import sys

import numpy as np
import pytest

from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.domains.language_table import LanguageTableTask
from lerobot_contrast.domains.language_table.config_language_table_sim import LanguageTableSimConfig
from lerobot_contrast.domains.language_table.language_table_sim import LanguageTableSim
from lerobot_contrast.eval import main
from lerobot_contrast.policies.pretrained import PolicyLoadError, PretrainedPolicy
from lerobot_contrast.record.observer import QuietObserver
from lerobot_contrast.spine.runner import RobotRunner
from tests.lerobot_helpers import save_act

RUN = ["--n_instances=2", "--seed=1", "--perturbations=[L,SB2]", "--max_episode_steps=12"]


@pytest.fixture(scope="module")
def act_path(tmp_path_factory):
    return save_act(tmp_path_factory.mktemp("act") / "model")


@pytest.fixture(scope="module")
def act_run(act_path, tmp_path_factory):
    run = tmp_path_factory.mktemp("runs") / "act"
    assert main([*RUN, f"--policy.path={act_path}", f"--output_dir={run}"]) == 0
    return run


def records(run):
    return [json.loads(line) for line in (run / "journal.jsonl").read_text().splitlines()]


def test_a_saved_lerobot_policy_runs_a_contrast_evaluation_in_the_simulator(act_run, act_path):
    done = [r for r in records(act_run) if r["status"] == "done"]
    assert {r["perturbation"] for r in done} >= {None, "L"}
    assert all(0 < r["steps"] <= 12 for r in done)
    summary = json.loads((act_run / "summary.json").read_text())
    assert summary["settings"]["policy"] == str(act_path) and summary["settings"]["robot"] == "language_table_sim"


class ActionLog(QuietObserver):
    """An episode observer that keeps the actions sent."""

    def start(self, context, features, pose_keys):
        self.actions = []

    def step(self, timestamp_s, observation, action):
        self.actions.append(action)


def replay(act_path, instance: Instance, index: int):
    robot = LanguageTableSim(LanguageTableSimConfig())
    robot.connect()
    log = ActionLog()
    runner = RobotRunner(
        robot,
        PretrainedPolicy(robot, str(act_path)),
        LanguageTableTask(),
        operator=None,
        fps=None,
        max_steps=12,
        observers=[log],
    )
    context = TrialContext(
        index=index,
        instance=instance,
        base=instance,
        current=instance.scene,
        planned_cost=0.0,
        staging="in_place",
        rng=np.random.default_rng([1, index, 1]),
        planned_trials=1,
    )
    return runner(context), log.actions


def test_act_ignores_language_so_a_contrast_run_shows_it_unchanged_under_delta_l(act_run, act_path):
    journal = records(act_run)
    bases = {r["base_id"]: Instance.from_json(r["instance"]) for r in journal if r["perturbation"] is None}
    reworded = [r for r in journal if r["perturbation"] == "L" and r["status"] == "done"]
    assert reworded, "the plan should hold at least one ΔL trial"
    for record in reworded:
        instance = Instance.from_json(record["instance"])
        original_words = instance.derive(instruction=bases[record["base_id"]].instruction)
        assert original_words.instruction != instance.instruction
        as_run, actions = replay(act_path, instance, record["index"])
        in_original_words, original_actions = replay(act_path, original_words, record["index"])
        assert actions == original_actions
        assert as_run.success == in_original_words.success == record["success"]
        assert as_run.steps == in_original_words.steps == record["steps"]


def test_the_instruction_reaches_the_policy_as_task_and_reset_runs_between_trials(act_path):
    robot = LanguageTableSim(LanguageTableSimConfig())
    robot.connect()
    policy = PretrainedPolicy(robot, str(act_path))
    seen, resets = [], []
    select_action, reset = policy.policy.select_action, policy.policy.reset
    policy.policy.select_action = lambda batch, **kw: seen.append(batch["task"]) or select_action(batch, **kw)
    policy.policy.reset = lambda: resets.append(1) or reset()
    instance = LanguageTableTask().sample(1, np.random.default_rng(0))[0]
    context = TrialContext(0, instance, instance, instance.scene, 0.0, "reset", np.random.default_rng(0), 1)
    robot.stage_scene(instance.scene)
    policy.reset(context)
    action = policy.act(robot.get_observation())
    assert set(action) == {"delta_x", "delta_y"}
    assert seen == [[instance.instruction]] and resets == [1]


def test_a_fresh_policy_type_is_built_from_the_robots_features(tmp_path):
    run = tmp_path / "run"
    assert (
        main(
            [
                "--n_instances=1",
                "--perturbations=[L]",
                "--max_episode_steps=3",
                "--policy.type=act",
                "--policy.device=cpu",
                f"--output_dir={run}",
            ]
        )
        == 0
    )
    assert records(run)[0]["steps"] == 3


def test_rename_map_feeds_robot_keys_to_the_policys_features(tmp_path, capsys):
    policy = save_act(tmp_path / "front", camera_key="observation.images.front")
    base = ["--n_instances=1", "--perturbations=[L]", "--max_episode_steps=3", f"--policy.path={policy}"]
    assert main([*base, f"--output_dir={tmp_path / 'a'}"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "observation.images.front" in err and "--rename_map" in err
    assert not (tmp_path / "a").exists()
    rename = '--rename_map={"observation.images.top": "observation.images.front"}'
    assert main([*base, rename, f"--output_dir={tmp_path / 'b'}"]) == 0


def test_a_policy_path_that_holds_no_policy_is_a_one_line_error(tmp_path):
    # A process of its own, so that LeRobot's log lines, which go to the real stderr, would show.
    command = [sys.executable, "-m", "lerobot_contrast.eval", "--n_instances=1", "--rerun=false"]
    done = subprocess.run(
        [*command, f"--policy.path={tmp_path}", f"--output_dir={tmp_path / 'run'}"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "--policy.path" in done.stderr and "save_pretrained" in done.stderr, (
        done.stderr
    )


def test_loading_refuses_a_robot_without_the_policys_camera(act_path):
    robot = LanguageTableSim(LanguageTableSimConfig(camera=False))
    with pytest.raises(PolicyLoadError, match="observation.images.top"):
        PretrainedPolicy(robot, str(act_path))


@pytest.mark.parametrize("value", ["/nonexistent", "./no/model", "~/no-model", "runs/no/model"])
def test_a_path_like_policy_path_that_exists_nowhere_is_no_such_directory(tmp_path, capsys, value):
    assert main(["--n_instances=1", f"--policy.path={value}", f"--output_dir={tmp_path / 'run'}"]) == 2
    err = capsys.readouterr().err
    assert (
        err
        == f"error: --policy.path: no such directory: {value}; give a directory written by save_pretrained or a Hub repo id\n"
    )
    assert not (tmp_path / "run").exists()


def test_a_policy_whose_state_does_not_fit_the_robot_is_refused_before_the_run_directory(tmp_path, capsys):
    policy = save_act(tmp_path / "act2")
    config = json.loads((policy / "config.json").read_text())
    config["input_features"]["observation.state"]["shape"] = [2]
    (policy / "config.json").write_text(json.dumps(config))
    run = tmp_path / "run"
    assert main(["--n_instances=1", "--max_episode_steps=3", f"--policy.path={policy}", f"--output_dir={run}"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "observation.state" in err and "(2,)" in err and "(4,)" in err
    assert not run.exists()


def test_images_of_another_size_are_resized_when_the_view_is_the_same_and_refused_otherwise():
    from lerobot.configs.types import FeatureType, PolicyFeature
    from lerobot.policies import make_policy_config
    from lerobot.utils.import_utils import register_third_party_plugins

    from lerobot_contrast.policies.pretrained import _check_inputs, robot_dataset_features

    register_third_party_plugins()  # tabletop_pointer, as every lerobot-* command finds it
    features = robot_dataset_features(LanguageTableSim(LanguageTableSimConfig()))  # a 180x320 camera
    small = {
        "observation.images.top": PolicyFeature(type=FeatureType.VISUAL, shape=(3, 72, 128)),
        "observation.state": PolicyFeature(type=FeatureType.STATE, shape=(4,)),
    }
    pointer = make_policy_config("tabletop_pointer", input_features=dict(small))  # resizes any frame to 72x128
    assert _check_inputs(pointer, features, {}) == {}
    act = make_policy_config("act", input_features=dict(small))  # the same 16:9 view, smaller: the evaluator scales
    assert _check_inputs(act, features, {}) == {"observation.images.top": (72, 128)}
    square = {**small, "observation.images.top": PolicyFeature(type=FeatureType.VISUAL, shape=(3, 72, 72))}
    with pytest.raises(PolicyLoadError, match=r"observation.images.top has shape \(3, 72, 72\).*\(3, 180, 320\)"):
        _check_inputs(make_policy_config("act", input_features=square), features, {})
    grey = {**small, "observation.images.top": PolicyFeature(type=FeatureType.VISUAL, shape=(1, 72, 128))}
    with pytest.raises(PolicyLoadError, match=r"\(1, 72, 128\)"):
        _check_inputs(make_policy_config("tabletop_pointer", input_features=grey), features, {})


def test_an_act_trained_on_smaller_frames_sees_the_camera_scaled_to_its_size(tmp_path, capsys):
    policy = save_act(tmp_path / "act_small")
    config = json.loads((policy / "config.json").read_text())
    config["input_features"]["observation.images.top"]["shape"] = [3, 90, 160]
    (policy / "config.json").write_text(json.dumps(config))
    robot = LanguageTableSim(LanguageTableSimConfig())
    loaded = PretrainedPolicy(robot, path=str(policy))
    assert "observation.images.top frames of 320x180 are resized to 160x90" in capsys.readouterr().out
    seen, select_action = [], loaded.policy.select_action
    loaded.policy.select_action = lambda batch: (
        seen.append(batch["observation.images.top"].shape) or select_action(batch)
    )
    robot.connect()
    try:
        loaded.act(robot.get_observation())
    finally:
        robot.disconnect()
    assert [tuple(shape) for shape in seen] == [(1, 3, 90, 160)]
