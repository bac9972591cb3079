"""Staging flags that cannot work are refused in one line before anything runs."""

import io
import sys

import pytest

from lerobot_contrast.eval import main

SIM = ["--task=so101_blocks", "--robot.type=language_table_sim", "--n_instances=1", "--policy.type=random"]


@pytest.mark.parametrize(
    ("flags", "said"),
    [
        (["--operator=auto", "--cost=measured"], "--cost=measured needs --operator=console"),
        (
            ["--operator=console", "--cost=measured", "--task=language_table"],
            "--cost=measured needs a calibrated camera",
        ),
        (["--operator=console", "--staging.calibration=nowhere.json"], "nowhere.json: no table calibration"),
        (["--operator=console", "--staging.viewer=tv"], "--staging.viewer: unknown 'tv'"),
        (["--operator=console", "--cost=measured", "--task=vln", "--robot.type=vln_sim"], "the apartment has none"),
    ],
)
def test_staging_that_cannot_work_is_one_line(flags, said, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "stdin", io.StringIO(""))
    assert main([*SIM, *flags, f"--output_dir={tmp_path / 'run'}"]) == 2
    error = capsys.readouterr().err.strip()
    assert said in error and "\n" not in error
    assert not (tmp_path / "run").exists()
