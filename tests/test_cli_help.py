"""`python -m lerobot_contrast.eval --help` reads as a person needs it, and flags take LeRobot's space form too."""

import re
from pathlib import Path

from lerobot_contrast.eval import main
from lerobot_contrast.policies import DEFAULT_POLICY


def help_of(capsys, *args: str) -> list[str]:
    assert main([*args, "--help"]) == 0
    return capsys.readouterr().out.splitlines()


def flag_blocks(lines: list[str]) -> dict[str, str]:
    """Each `  --flag TYPE` line with the description lines under it."""
    blocks: dict[str, str] = {}
    name = None
    for line in lines:
        if line.startswith("  --"):
            name = line.split()[0]
            blocks[name] = ""
        elif name is not None and line.startswith("      "):
            blocks[name] += " " + line.strip()
    return blocks


def test_help_lists_the_commands_own_flags_first_each_with_one_default(capsys):
    lines = help_of(capsys)
    flags = [line.split()[0] for line in lines if line.startswith("  --")]
    assert flags[:3] == ["--task", "--families", "--strategy"] and "--n_instances" in flags[:10]
    assert len(lines) < 150 and flags[-1] == "--robot.type"  # robot fields only once a type is chosen
    blocks = flag_blocks(lines)
    assert all(len(re.findall(r"default", text, flags=re.I)) <= 1 for text in blocks.values()), blocks
    assert f"(default: {DEFAULT_POLICY})" in blocks["--policy.type"] and "so101_follower" in blocks["--robot.type"]


def test_help_shows_the_fields_of_the_chosen_robot_type_only(capsys):
    blocks = flag_blocks(help_of(capsys, "--robot.type", "so101_follower"))
    assert "--robot.port" in blocks and "--robot.id" in blocks and "--robot.can_interface" not in blocks
    assert blocks["--robot.port"].strip() == "(required)"


def test_a_mistyped_flag_suggests_the_nearest_one(capsys):
    assert main(["--n_instance=3", "--dry_run=true"]) == 2
    assert capsys.readouterr().err == "error: unknown flag --n_instance; did you mean --n_instances?\n"


def test_flags_take_the_space_form(capsys):
    assert main(["--n_instances", "2", "--perturbations", "LB1", "--dry_run", "true"]) == 0
    spaced = capsys.readouterr().out
    assert main(["--n_instances=2", "--perturbations=LB1", "--dry_run=true"]) == 0
    assert spaced == capsys.readouterr().out and "ΔLB1" in spaced


def test_every_command_takes_both_flag_forms_and_booleans_as_true_or_false():
    from lerobot_contrast.publish import parse_args as publish_args
    from lerobot_contrast.report import parse_args as report_args
    from lerobot_contrast.review import ReviewConfig
    from lerobot_contrast.spine.flags import parse_config

    for argv in (
        ["run", "--repo_id=u/n", "--private=true"],
        ["run", "--repo_id", "u/n", "--private", "true"],
        ["--private", "run", "--repo_id", "u/n"],  # alone, a boolean flag means true
    ):
        args = publish_args(argv)
        assert (args.run_dir, args.repo_id, args.private) == (Path("run"), "u/n", True)
    assert publish_args(["run", "--repo_id=u/n", "--private=false"]).private is False
    review = parse_config(ReviewConfig, ["run", "--save_only=true", "--web_port", "9191"], positional="run_dir")
    assert (review.run_dir, review.save_only, review.web_port) == (Path("run"), True, 9191)
    report = report_args(["a", "b", "--metric", "success"])
    assert (report.runs, report.metric) == (["a", "b"], "success")


def test_every_command_answers_help_in_one_layout(capsys):
    from lerobot_contrast.publish import main as publish
    from lerobot_contrast.report import main as report
    from lerobot_contrast.review import main as review
    from lerobot_contrast.sweep.command import main as sweep

    for command, first in ((publish, "--run_dir"), (report, "--runs"), (review, "--run_dir"), (sweep, "--sweep")):
        assert command(["--help"]) == 0
        lines = capsys.readouterr().out.splitlines()
        assert lines[0].startswith("usage: python -m lerobot_contrast.") and "--flag=value | --flag value" in lines[0]
        blocks = flag_blocks(lines)
        assert next(iter(blocks)) == first and all(text.strip() for text in blocks.values()), blocks


def test_flag_mistakes_get_one_line_in_every_command(capsys, tmp_path):
    from lerobot_contrast.publish import main as publish
    from lerobot_contrast.report import main as report
    from lerobot_contrast.review import main as review

    cases = [
        (publish, ["run", "--repo=u/n"], "error: unknown flag --repo; did you mean --repo_id?\n"),
        (review, ["run", "--save_only=perhaps"], "error: --save_only: couldn't parse 'perhaps' into a bool"),
        (report, ["run", "--metrc=spl"], "error: unknown flag --metrc; did you mean --metric?\n"),
        (report, ["run", "--metric=speed"], "error: --metric must be one of"),
    ]
    for command, argv, message in cases:
        assert command(argv) == 2
        err = capsys.readouterr().err
        assert err.startswith(message) and err.count("\n") == 1, err


def test_an_unknown_robot_or_policy_field_names_the_valid_ones_in_one_line(capsys):
    sim = "--robot.type=language_table_sim"
    cases = [
        ([sim, "--robot.camra=true"], "unknown flag --robot.camra; did you mean --robot.camera?"),
        ([sim, "--robot.nonexistent=1"], "unknown flag --robot.nonexistent; --robot.* takes --robot.calibration_dir, "),
        (["--policy.nonexistent=1"], "unknown flag --policy.nonexistent; did you mean --policy.noise_std?"),
        (["--robot.port=x"], "--robot.port needs --robot.type=TYPE"),
    ]
    for argv, message in cases:
        assert main([*argv, "--dry_run=true"]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"error: {message}") and err.count("\n") == 1, err


# Runs a command in a fresh interpreter and says which heavy libraries its answer waited for.
LOADED = """import runpy, sys
sys.argv = [sys.argv[1], *sys.argv[2:]]
try:
    runpy.run_module(sys.argv[0], run_name="__main__")
except SystemExit as exit:
    print(exit.code, *sorted(m for m in ("torch", "scipy", "ray", "pandas", "lerobot.robots") if m in sys.modules))
"""


def test_a_mistyped_flag_is_answered_before_lerobot_torch_or_ray_load():
    """The check that makes a typo's answer instant (the seconds are measured by scripts/bench/bench_flag_errors.py)."""
    import subprocess
    import sys

    cases = [
        ("lerobot_contrast.eval", ["--n_instance=3"], "--n_instances"),
        ("lerobot_contrast.eval", ["--robot.port=x"], "--robot.type=TYPE"),
        ("lerobot_contrast.sweep", ["sweep.yaml", "--max_retrie=2"], "--max_retries"),
    ]
    for module, argv, named in cases:
        run = subprocess.run([sys.executable, "-c", LOADED, module, *argv], capture_output=True, text=True)
        assert named in run.stderr and run.stderr.count("\n") == 1, run.stderr
        assert run.stdout.split() == ["2"], f"{module} {argv}: exit code, then what loaded first: {run.stdout}"
