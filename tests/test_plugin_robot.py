"""A third-party robot package, installed beside this one, is discovered by LeRobot's plugin mechanism and driven
by the evaluator; when its link drops, the trial is aborted and the session reconnects or stops resumably."""

import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

PACKAGE = "lerobot_robot_flaky"
CONFIG = """
from dataclasses import dataclass

from lerobot.robots import RobotConfig

from lerobot_contrast.domains.language_table.config_language_table_sim import LanguageTableSimConfig


@RobotConfig.register_subclass("flaky_tabletop")
@dataclass(kw_only=True)
class FlakyTabletopConfig(LanguageTableSimConfig):
    fail_at_action: int = -1
    can_reconnect: bool = True
"""
ROBOT = '''
from lerobot_contrast.domains.language_table.language_table_sim import LanguageTableSim

from .config_flaky_tabletop import FlakyTabletopConfig


class FlakyTabletop(LanguageTableSim):
    """The simulated tabletop behind a link that drops after a set number of actions."""

    config_class = FlakyTabletopConfig
    name = "flaky_tabletop"
    actions = 0

    def connect(self, calibrate=True):
        if FlakyTabletop.actions and not self.config.can_reconnect:
            raise ConnectionError("no route to host 10.0.0.7")
        super().connect(calibrate)

    def send_action(self, action):
        FlakyTabletop.actions += 1
        if FlakyTabletop.actions == self.config.fail_at_action:
            raise ConnectionError("link lost")
        return super().send_action(action)
'''


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """A site directory holding the plugin as an installed distribution (package + dist-info metadata)."""
    root = tmp_path_factory.mktemp("site")
    package = root / PACKAGE
    package.mkdir()
    (package / "__init__.py").write_text(
        "from .config_flaky_tabletop import FlakyTabletopConfig\nfrom .flaky_tabletop import FlakyTabletop\n"
    )
    (package / "config_flaky_tabletop.py").write_text(textwrap.dedent(CONFIG))
    (package / "flaky_tabletop.py").write_text(textwrap.dedent(ROBOT))
    info = root / f"{PACKAGE}-0.1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {PACKAGE}\nVersion: 0.1.0\n")
    (info / "top_level.txt").write_text(PACKAGE + "\n")
    return root


def evaluate(site: Path, run: Path, *flags: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(site), *sys.path])}
    args = ["--n_instances=2", "--seed=5", "--perturbations=[L,SB2]", "--max_episode_steps=40", f"--output_dir={run}"]
    args += ["--policy.type=oracle", "--rerun=false"]  # the robot is under test: the cheapest policy, no recordings
    return subprocess.run(
        [sys.executable, "-m", "lerobot_contrast.eval", "--robot.type=flaky_tabletop", *args, *flags],
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )


def journal(run: Path) -> list[dict]:
    return [json.loads(line) for line in (run / "journal.jsonl").read_text().splitlines()]


def test_an_installed_plugin_robot_is_discovered_and_driven(site, tmp_path):
    result = evaluate(site, tmp_path / "run")
    assert result.returncode == 0, result.stderr
    done = [r for r in journal(tmp_path / "run") if r["status"] == "done"]
    assert done and all(r["steps"] > 0 for r in done)
    assert json.loads((tmp_path / "run" / "summary.json").read_text())["settings"]["robot"] == "flaky_tabletop"


def test_a_dropped_link_aborts_the_trial_and_the_session_reconnects(site, tmp_path):
    result = evaluate(site, tmp_path / "run", "--robot.fail_at_action=5")
    assert result.returncode == 0, result.stderr
    records = journal(tmp_path / "run")
    assert records[0]["status"] == "aborted" and records[0]["extra"]["ended_by"] == "disconnected"
    assert records[0]["steps"] == 4
    assert any(r["status"] == "done" for r in records[1:])


@pytest.mark.slow
def test_a_robot_that_cannot_reconnect_stops_the_session_resumably(site, tmp_path):
    run = tmp_path / "run"
    result = evaluate(site, run, "--robot.fail_at_action=5", "--robot.can_reconnect=false")
    assert result.returncode == 2
    assert "disconnected (link lost); trying to reconnect for up to 5 s" in result.stdout
    assert "aborted: the robot disconnected after 4 steps" in result.stdout
    assert (
        "could not reconnect within 5 s (no route to host 10.0.0.7)" in result.stderr
        and f"continue the run with --output_dir={run} --resume=true" in result.stderr
    )
    assert [r["status"] for r in journal(run)] == ["aborted"]
    summary = json.loads((run / "summary.json").read_text())
    assert summary["complete"] is False and summary["overall"]["aborted"] == 1
    kept = tmp_path / "kept"
    shutil.copytree(run, kept)
    # Back, with robot settings changed: the aborted trial runs again.
    resumed = evaluate(site, run, "--resume=true", "--robot.can_reconnect=true", "--robot.fail_at_action=-1")
    assert resumed.returncode == 0, resumed.stderr
    assert "trial 0 was aborted when the robot disconnected; it runs again" in resumed.stdout
    assert [r["status"] for r in journal(run)][0] == "done" and "aborted" not in {r["status"] for r in journal(run)}
    flags = ("--resume=true", "--robot.can_reconnect=true", "--robot.fail_at_action=-1", "--rerun_aborted=false")
    resumed = evaluate(site, kept, *flags)
    assert resumed.returncode == 0, resumed.stderr
    assert journal(kept)[0]["status"] == "aborted" and len(journal(kept)) == len(journal(run))
    assert json.loads((kept / "summary.json").read_text())["overall"]["aborted"] == 1
