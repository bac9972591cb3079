"""Runs to look at: a small contrast run with a dataset (videos), the same plan under a second policy (A/B), and
the report of both, made once per session by the real commands."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

EVAL = [sys.executable, "-m", "lerobot_contrast.eval", "--n_instances=4", "--seed=3", "--rerun=false"]
# Noisy and deaf to half of the changed wording: some perturbed trials flip against their originals.
NOISY = ["--policy.type=oracle", "--policy.noise_std=0.01", "--policy.language_blind=0.5"]


def evaluate(output_dir: Path, *flags: str) -> Path:
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    done = subprocess.run([*EVAL, *flags, f"--output_dir={output_dir}"], capture_output=True, text=True, env=env,
                          timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    return output_dir


@pytest.fixture(scope="session")
def runs(tmp_path_factory) -> dict[str, Path]:
    """`noisy`: recorded with a dataset; `oracle`: the same plan, another policy, no dataset; `session`: an A/B
    session of both policies (--policies); `report` and `session_report`: report.md of the noisy run alone, and of
    the session."""
    root = tmp_path_factory.mktemp("view")
    noisy = evaluate(root / "noisy", *NOISY, "--record_dataset=true")
    oracle = evaluate(root / "oracle", "--policy.type=oracle")
    session = evaluate(root / "session", "--policies=oracle,oracle:noise_std=0.01:language_blind=0.5")
    return {
        "noisy": noisy,
        "oracle": oracle,
        "session": session,
        "report": report(noisy, root / "report"),
        "session_report": report(session, root / "session_report"),
    }


def report(run: Path, output_dir: Path) -> Path:
    done = subprocess.run([sys.executable, "-m", "lerobot_contrast.report", str(run), f"--output_dir={output_dir}"],
                          capture_output=True, text=True, timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    return output_dir / "report.md"


@pytest.fixture
def copy_of(tmp_path):
    def copy(run: Path) -> Path:
        target = tmp_path / run.name
        shutil.copytree(run, target)
        return target

    return copy


@pytest.fixture
def in_progress(runs, copy_of) -> tuple[Path, list[str]]:
    """A copy of the noisy run as it was after 5 trials (summary not complete), and its whole journal's lines."""
    run = copy_of(runs["noisy"])
    journal = run / "journal.jsonl"
    lines = journal.read_text().splitlines(keepends=True)
    summary = json.loads((run / "summary.json").read_text())
    (run / "summary.json").write_text(json.dumps({**summary, "complete": False}))
    journal.write_text("".join(lines[:5]))
    return run, lines


def report_rows(report_md: Path, title: str) -> list[list[str]]:
    """The rows of the table in report.md's section `title` (a ## or ### heading; its header row left out)."""
    section = report_md.read_text(encoding="utf-8").split(f"## {title}", 1)[1].splitlines()[1:]
    lines = []
    for line in section:
        if line.startswith("#"):
            break
        if line.startswith("|") and not line.startswith("|---"):
            lines.append(line)
    return [[cell.strip() for cell in line.strip().strip("|").split("|")] for line in lines[1:]]
