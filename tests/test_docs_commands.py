"""Every command in the shell blocks of the README and the documentation stays true: each `python -m` module runs,
as a dry run or `--help`."""

import re
import runpy
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from tests.docs_pages import ROOT, code_blocks


def shell_commands() -> list[list[str]]:
    """The pages' bash blocks as commands split into words: continuations joined, comments and placeholders
    (`<...>`, `[...]`, `...`) dropped, `a && b` as two commands."""
    lines = "\n".join(code_blocks("bash")).replace("\\\n", " ").splitlines()
    commands = []
    for line in lines:
        words = [
            w for w in shlex.split(re.sub(r"<[^>]*>|\[[^\]]*\]", "", line), comments=True) if w not in ("...", "&")
        ]
        while "&&" in words:
            commands.append(words[: words.index("&&")])
            words = words[words.index("&&") + 1 :]
        commands.append(words)
    return [c for c in commands if c]


def python_commands() -> list[list[str]]:
    """`MODULE ARGS...` of each `python -m` command (but `-m venv`)."""
    return [c[2:] for c in shell_commands() if c[0].endswith("python") and c[1] == "-m"]


def lerobot_commands(program: str) -> list[list[str]]:
    """The flags of each command of LeRobot's `program` (`lerobot-eval`, `lerobot-train`)."""
    return [c[1:] for c in shell_commands() if Path(c[0]).name == program]


def as_check(module: str, args: list[str]) -> list[str]:
    """An evaluation runs as a dry run (it plans, needs no robot, policy or network); everything else as --help."""
    if module == "lerobot_contrast.eval" and "--help" not in args and not any("hub:" in a for a in args):
        return [a for a in args if not a.startswith("--dry_run")] + ["--dry_run=true"]
    return ["--help"]


def test_every_python_command_in_the_docs_uses_the_virtual_environment():
    bare = [c for c in shell_commands() if "python" in c[0] and c[0] != ".venv/bin/python" and c[1:3] != ["-m", "venv"]]
    assert not bare, f"commands outside .venv/bin/python: {bare}"


def test_the_docs_name_the_commands_they_should():
    modules = {command[0] for command in python_commands()}
    assert {"lerobot_contrast.eval", "lerobot_contrast.review", "lerobot_contrast.report"} <= modules
    assert {"lerobot_contrast.publish", "lerobot_contrast.sweep", "lerobot_robot_locobot.host"} <= modules


@pytest.mark.parametrize("command", python_commands(), ids=lambda c: " ".join(c)[:80])
def test_each_command_runs_in_dry_run_or_help_form(command, tmp_path, monkeypatch, capsys):
    module, args = command[0], as_check(command[0], command[1:])
    monkeypatch.chdir(tmp_path)
    task_file = next(b for b in code_blocks("yaml", [ROOT / "docs" / "tasks.md"]) if "name: my_table" in b)
    (tmp_path / "my_table.yaml").write_text(task_file, encoding="utf-8")  # the docs' complete task file
    for arg in args:  # a checkpoint of yours the command names by its path: a dry run needs the directory to exist
        if arg.startswith("--policy.path=") and arg.count("/") > 1:
            (tmp_path / arg.split("=", 1)[1]).mkdir(parents=True, exist_ok=True)
    monkeypatch.setattr(sys, "argv", [module, *args])
    with pytest.raises(SystemExit) as exited:
        runpy.run_module(module, run_name="__main__", alter_sys=True)
        raise SystemExit(0)
    out, err = capsys.readouterr()
    assert exited.value.code in (0, None), f"{module} {' '.join(args)} exited {exited.value.code}: {err[-500:]}"


@pytest.mark.parametrize("program", ["lerobot-eval", "lerobot-train"])
def test_every_lerobot_command_uses_flags_and_paths_that_exist(program):
    commands = lerobot_commands(program)
    flags = [flag.split("=", 1) for command in commands for flag in command]
    assert commands and {value for name, value in flags if name == "--env.type"} == {"language_table"}
    for name, value in flags:
        if name == "--policy.path" or (name == "--env.instances" and not value.startswith("outputs/")):
            assert (ROOT / value).is_dir(), f"{name}={value} is not a directory of this repository"
    shown = [Path(sys.executable).with_name(program), "--env.type=language_table", "--help"]
    usage = subprocess.run(shown, capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert usage.returncode == 0, usage.stderr[-2000:]
    known = set(re.findall(r"--[\w.]+", usage.stdout))
    # The env's, the evaluation's and the top-level flags; a policy's or dataset's depend on its type.
    checked = {name for name, _ in flags if not name.startswith(("--policy.", "--dataset."))}
    assert checked <= known, f"{program} does not know {checked - known}"
