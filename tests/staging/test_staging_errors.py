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


def test_the_console_says_how_to_open_the_staging_view(monkeypatch, capsys):
    import rerun as rr

    from lerobot_contrast.contrast.errors import UserError
    from lerobot_contrast.staging.setup import open_view

    monkeypatch.setattr(rr.RecordingStream, "serve_grpc", lambda self: "rerun+http://127.0.0.1:9999/proxy")
    assert open_view("serve") is not None
    assert "run `rerun --connect rerun+http://127.0.0.1:9999/proxy`" in capsys.readouterr().out
    assert open_view("none") is None

    def taken(self):
        raise RuntimeError("address in use")

    monkeypatch.setattr(rr.RecordingStream, "serve_grpc", taken)
    with pytest.raises(UserError, match="cannot serve the staging view .address in use.; use --staging.viewer=spawn"):
        open_view("serve")
