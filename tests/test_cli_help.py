"""`python -m lerobot_contrast.eval --help` reads as a person needs it, and flags take LeRobot's space form too."""

import re

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
