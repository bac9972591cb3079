"""The table of malformed inputs (issue 18): each bad flag or task file is refused with exit 2, one line naming
what is wrong, no traceback, and nothing left in the run directory."""

from __future__ import annotations

import json

import pytest

from lerobot_contrast.eval import main
from tests.domains.task_file.task_file_fixtures import CUPS
from tests.lerobot_helpers import save_act

# A run that would be quick, were it accepted: one base instance, the scripted oracle, no recordings.
QUICK = ["--n_instances=1", "--policy.type=oracle", "--rerun=false", "--max_episode_steps=5"]

# name -> (flags added to QUICK, what the one error line must say)
FLAGS = {
    "negative seed": (["--seed=-1"], "--seed must be a whole number >= 0, got -1"),
    "huge n_instances": (["--n_instances=99999999999999999999999", "--dry_run=true"], "more than 10000 base trials"),
    "huge repeats": (["--repeats=99999999999999999999", "--dry_run=true"], "more than 10000 base trials"),
    "zero max_episode_s": (["--max_episode_s=0"], "--max_episode_s must be a positive number, got 0"),
    "clock not an address": (["--clock=sim"], "--clock=sim: give wall, or the tcp://HOST:PORT a twin started with"),
    "negative max_episode_s": (["--max_episode_s=-1"], "--max_episode_s must be a positive number, got -1"),
    "nan max_episode_s": (["--max_episode_s=nan"], "--max_episode_s must be a positive number, got nan"),
    "zero fps": (["--fps=0"], "--fps must be a positive number, got 0"),
    "negative fps": (["--fps=-5"], "--fps must be a positive number, got -5"),
    "nan budget": (["--budget=nan"], "--budget must be a positive number, got nan; drop --budget for no limit"),
    "inf budget": (["--budget=inf"], "--budget must be a positive number, got inf"),
    "repeated perturbation": (["--perturbations=LB1,LB1"], "--perturbations: LB1 given more than once"),
    "repeated family": (["--families=separate,separate"], "--families: separate given more than once"),
    "rename_map for a scripted policy": (['--rename_map={"a": 1}'], "--rename_map: --policy.type=oracle"),
    "unknown operator": (["--operator=foo"], "--operator: unknown mode 'foo'; choose from: auto, console"),
    "negative noise": (["--policy.noise_std=-1"], "--policy.noise_std must be a number of metres >= 0"),
    "language_blind above 1": (["--policy.language_blind=2"], "--policy.language_blind is a probability"),
    "malformed repo_id": (["--push_to_hub=true", "--repo_id=bad"], "--repo_id must look like USER/NAME"),
}

# name -> (replacement in the CUPS task file, or text appended to it; what the one error line must say)
TASK_FILES = {
    "NUL byte": (("name: cups", "name: cu\0ps"), "cups.yaml:2: invalid YAML: character code 0"),
    "5,000-deep lists": ("extra: " + "[" * 5000 + "]" * 5000 + "\n", "nested too deeply"),
    "5,000-deep mappings": ("extra: " + "{a: " * 5000 + "1" + "}" * 5000 + "\n", "nested too deeply"),
    "NaN in bounds": (("x: [0, 1]", "x: [0, .nan]"), "workspace.bounds.x[1]: expected a number between"),
    "inf in bounds": (("x: [0, 1]", "x: [0, .inf]"), "got inf"),
    "-1e300 in bounds": (("x: [0, 1]", "x: [-1.0e+300, 1]"), "workspace.bounds.x[0]: expected a number"),
    "inf in storage": (
        ("min_spacing: 0.1", "min_spacing: 0.1\n  storage: [[0, .inf], [0, 1]]"),
        "workspace.storage[0][1]: expected a number between -1e+06 and 1e+06, got inf",
    ),
    "storage far away": (
        ("min_spacing: 0.1", "min_spacing: 0.1\n  storage: [[0, 0], [0, 1000]]"),
        "workspace.storage[1]: the storage point lies further from the workspace",
    ),
    "NaN tolerance": ("cost: {tolerance: .nan}\n", "cost.tolerance: expected a number between"),
    "tolerance larger than the workspace": ("cost: {tolerance: 5}\n", "cost.tolerance: a tolerance of 5 m"),
    "inf hand speed": ("cost: {hand_speed: .inf}\n", "cost.hand_speed: expected a number"),
    "NaN handling time": ("cost: {handling_time_s: {default: .nan}}\n", "cost.handling_time_s.default"),
    "NaN robot yaw": (
        ("min_spacing: 0.1", "min_spacing: 0.1\n  robot_start: [0.1, 0, .nan]"),
        "workspace.robot_start[2]: expected a number",
    ),
    "negative sampler seed": ("sampler: {seed: -5}\n", "sampler.seed: expected a whole number >= 0, got -5"),
}


def refused(argv: list[str], run, capsys, says: str) -> str:
    """Run eval; it must exit 2 with exactly one `error:` line containing `says`, and write no run directory."""
    assert main([*argv, f"--output_dir={run}"]) == 2
    out, err = capsys.readouterr()
    assert err.startswith("error: ") and err.count("\n") == 1, err
    assert says in err, err
    assert "Traceback" not in out + err
    assert not run.exists()
    return err


@pytest.mark.timeout(120)
@pytest.mark.parametrize("case", sorted(FLAGS))
def test_a_malformed_flag_is_one_line_and_leaves_nothing(case, tmp_path, capsys):
    flags, says = FLAGS[case]
    refused([*QUICK, *flags], tmp_path / "run", capsys, says)


@pytest.mark.parametrize("case", sorted(TASK_FILES))
def test_a_malformed_task_file_is_one_line_and_leaves_nothing(case, tmp_path, capsys):
    change, says = TASK_FILES[case]
    text = CUPS.replace(*change) if isinstance(change, tuple) else CUPS + change
    assert text != CUPS
    path = tmp_path / "cups.yaml"
    path.write_text(text, encoding="utf-8")
    refused([f"--task={path}", "--n_instances=1", "--policy.type=random"], tmp_path / "run", capsys, says)


def test_an_output_dir_that_is_a_file_is_refused_and_left_alone(tmp_path, capsys):
    existing = tmp_path / "results.txt"
    existing.write_text("keep me")
    assert main([*QUICK, f"--output_dir={existing}"]) == 2
    err = capsys.readouterr().err
    assert err == f"error: --output_dir: {existing} is a file, not a directory; choose a directory\n"
    assert existing.read_text() == "keep me" and sorted(p.name for p in tmp_path.iterdir()) == ["results.txt"]


def test_a_hub_plan_without_network_is_one_line(hub, tmp_path, capsys):
    hub.stop()  # the endpoint refuses every connection, as with no network
    refused(["--plan=hub:USER/NAME", "--dry_run=true"], tmp_path / "run", capsys, "hub:USER/NAME: cannot reach the Hub")


@pytest.fixture(scope="module")
def act_path(tmp_path_factory):
    return save_act(tmp_path_factory.mktemp("act") / "model")


def test_a_policy_config_without_input_features_is_one_line(act_path, tmp_path, capsys):
    policy = tmp_path / "no_inputs"
    policy.mkdir()
    for part in act_path.iterdir():
        (policy / part.name).write_bytes(part.read_bytes())
    config = json.loads((policy / "config.json").read_text())
    config["input_features"] = {}
    (policy / "config.json").write_text(json.dumps(config))
    argv = ["--n_instances=1", "--max_episode_steps=3", f"--policy.path={policy}"]
    refused(argv, tmp_path / "run", capsys, f"--policy.path={policy}: cannot build the policy")


@pytest.mark.parametrize(
    ("rename_map", "says"),
    [
        ('{"a": 1}', "--rename_map: the robot gives no 'a'"),
        ('{"observation.images.top": "1"}', "'observation.images.top' is mapped to '1', which the policy does not"),
    ],
)
def test_a_rename_map_that_maps_nothing_real_is_one_line(act_path, tmp_path, capsys, rename_map, says):
    argv = ["--n_instances=1", "--max_episode_steps=3", f"--policy.path={act_path}", f"--rename_map={rename_map}"]
    refused(argv, tmp_path / "run", capsys, says)
