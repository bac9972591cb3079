"""Sweep files: a grid and a list of cells expand into named cells, and bad files are refused in one line before
anything runs (no Ray here)."""

from pathlib import Path

import pytest
import yaml

from lerobot_contrast.sweep.cells import cell_name, read_sweep_file, studies_dir, sweep_cells, sweep_file_path
from lerobot_contrast.sweep.command import main

SMALL = {
    "eval": {"n_instances": 2, "max_episode_steps": 20, "rerun": False, "policy": {"type": "oracle"}},
    "grid": {"seed": [0, 1], "policy.noise_std": [0.0, 0.01]},
    "cells": [
        {"strategy": "standard"},
        {"name": "lb", "strategy": "contrast", "perturbations": ["LB1", "LB2"]},
    ],
}


def write(tmp_path: Path, spec: dict) -> Path:
    path = tmp_path / "sweep.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False), encoding="utf-8")
    return path


def test_every_grid_combination_of_every_cell_is_a_run_directory_named_by_its_settings(tmp_path):
    path = write(tmp_path, SMALL)
    cells = sweep_cells(path, read_sweep_file(path), tmp_path / "out")
    assert [c.name for c in cells[:2]] == [
        "strategy=standard,seed=0,policy.noise_std=0.0",
        "strategy=standard,seed=0,policy.noise_std=0.01",
    ]
    assert cells[4].name == "lb,seed=0,policy.noise_std=0.0" and cells[4].label == "lb"
    assert len(cells) == 8 and len({c.name for c in cells}) == 8
    lb = cells[7].config
    assert (lb.strategy, lb.perturbations, lb.seed, lb.policy.noise_std) == ("contrast", ["LB1", "LB2"], 1, 0.01)
    assert lb.policy.type == "oracle" and lb.n_instances == 2 and lb.robot.type == "language_table_sim"
    assert lb.output_dir == (tmp_path / "out").resolve() / cells[7].name
    assert cells[7].settings == {
        "strategy": "contrast",
        "perturbations": ["LB1", "LB2"],
        "seed": 1,
        "policy.noise_std": 0.01,
    }


def test_every_group_of_flags_can_be_written_nested_or_dotted(tmp_path):
    spec = {"eval": {"policy.type": "oracle", "stop": {"width": 0.3}}, "cells": [{"stop.alpha": 0.1}]}
    path = write(tmp_path, spec)
    (cell,) = sweep_cells(path, read_sweep_file(path), tmp_path / "out")
    assert (cell.config.policy.type, cell.config.stop.width, cell.config.stop.alpha) == ("oracle", 0.3, 0.1)
    assert cell.name == "stop.alpha=0.1"


def test_cell_names_are_filesystem_safe_and_bounded():
    assert cell_name(None, {"policy.path": "user/model v2"}, {"seed": 0}) == "policy.path=user_model_v2,seed=0"
    long = cell_name(None, {"policy.path": "x" * 400}, {})
    assert len(long) == 150 and long != cell_name(None, {"policy.path": "x" * 399 + "y"}, {})


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"eval": {"n_instance": 2}}, "eval: unknown eval setting 'n_instance'; did you mean n_instances?"),
        ({"grid": {"output_dir": ["a"]}}, "grid: output_dir is set by the sweep for every cell; remove it"),
        ({"grid": {"seed": 3}}, "grid: seed must be a non-empty list of values"),
        ({"cells": [{"name": "a"}, {"name": "a"}]}, "two cells are both named a"),
        ({"cells": [{"seed": 3}]}, "cells: entry 1 sets seed, which the grid also sets"),
        ({"cells": [{"strategy": "standard", "n_instances": "many"}]}, "`n_instances`"),
        ({"sweeps": 1}, "unknown key 'sweeps'"),
        (
            {"cells": [{"robot": {"type": "so101_follower", "port": "/dev/ttyACM0"}}]},
            "robot.type=so101_follower is a real robot, one physical place; a sweep runs simulated cells only",
        ),
    ],
)
def test_a_bad_sweep_file_is_refused_in_one_line_before_anything_starts(tmp_path, capsys, change, message):
    path = write(tmp_path, SMALL | change)
    assert main([str(path), f"--output_dir={tmp_path / 'out'}"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {path}: ") and message in err and err.count("\n") == 1, err
    assert not (tmp_path / "out").exists()


def test_dry_run_lists_the_cells_and_their_planned_trials(tmp_path, capsys):
    path = write(tmp_path, SMALL)
    assert main([str(path), f"--output_dir={tmp_path / 'out'}", "--dry_run=true"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "strategy=standard,seed=0,policy.noise_std=0.0: 2 planned trials"
    assert out[-1] == f"8 cells into {tmp_path / 'out'}" and not (tmp_path / "out").exists()


def test_help_lists_the_sweep_flags(capsys):
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: python -m lerobot_contrast.sweep SWEEP.yaml")
    assert all(
        f"  --{flag} " in out
        for flag in ("output_dir", "resume", "max_retries", "ray.address", "ray.num_cpus", "ray.gpus_per_cell")
    )


def test_a_dry_run_names_a_policy_path_that_is_not_there(tmp_path, capsys):
    missing = tmp_path / "no_such_model"
    spec = SMALL | {"eval": {**SMALL["eval"], "policy": {"path": str(missing)}}}
    assert main([str(write(tmp_path, spec)), f"--output_dir={tmp_path / 'out'}", "--dry_run", "true"]) == 2
    err = capsys.readouterr().err
    assert f"--policy.path: no such directory: {missing}" in err and err.count("\n") == 1, err


@pytest.mark.parametrize(("value", "shown"), [("1.5", "1.5"), ("0", "0"), ("-0.5", "-0.5")])
def test_a_gpu_share_ray_cannot_give_is_refused_in_one_line(tmp_path, capsys, value, shown):
    out = tmp_path / "out"
    assert main([str(write(tmp_path, SMALL)), f"--output_dir={out}", f"--ray.gpus_per_cell={value}"]) == 2
    err = capsys.readouterr().err
    expected = f"--ray.gpus_per_cell must be a fraction of one GPU (0.25) or a whole number of GPUs, got {shown}"
    assert expected in err and err.count("\n") == 1, err
    assert not out.exists()


def test_a_shipped_study_is_named_without_its_path_and_a_file_of_that_name_here_wins(tmp_path, monkeypatch):
    assert sweep_file_path(Path("paper_sim")) == studies_dir() / "paper_sim.yaml"
    assert sweep_file_path(Path("paper_vln.yaml")) == studies_dir() / "paper_vln.yaml"
    assert read_sweep_file(sweep_file_path(Path("paper_sim")))["eval"]["task"] == "language_table"
    monkeypatch.chdir(tmp_path)
    write(tmp_path, SMALL).rename(tmp_path / "paper_sim.yaml")
    assert sweep_file_path(Path("paper_sim.yaml")) == Path("paper_sim.yaml")
    assert sweep_file_path(Path("nowhere/paper_sim")) == Path("nowhere/paper_sim")
