"""Sweeps on a real local Ray (2 CPUs and one declared GPU, one session shared by the module): every cell run once,
results gathered, a bad cell reported in one line, cells on cuda given their GPU share, and nothing lost or
duplicated when a worker or the whole sweep is killed."""

import json
import logging
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pandas as pd
import psutil
import pytest
import ray
import yaml

from lerobot_contrast.eval import planned_evaluation
from lerobot_contrast.record.journal import read_journal
from lerobot_contrast.report import main as report_main
from lerobot_contrast.sweep.cells import read_sweep_file, sweep_cells
from lerobot_contrast.sweep.command import main

ORACLE = {"max_episode_steps": 30, "rerun": False, "policy": {"type": "oracle"}}
SMALL = {
    "eval": {"n_instances": 2, **ORACLE},
    "grid": {"seed": [0, 1]},
    "cells": [
        {"name": "standard", "strategy": "standard"},
        {"name": "lb", "strategy": "contrast", "perturbations": ["LB1", "LB2"]},
    ],
}
# Cells long enough (21 planned trials each) to be killed in the middle; three cells on two CPUs, so that one waits
# for a CPU when the sweep is killed.
LONG = {"eval": {"n_instances": 3, **ORACLE, "max_episode_steps": 40}, "grid": {"seed": [0, 1, 2]}}


@pytest.fixture(scope="module")
def local_ray():
    # One logical GPU: Ray schedules GPU cells on it and sets their CUDA_VISIBLE_DEVICES without any hardware.
    ray.init(num_cpus=2, num_gpus=1, include_dashboard=False, log_to_driver=False, logging_level=logging.WARNING)
    yield ray.get_runtime_context().gcs_address
    ray.shutdown()


def write(tmp_path: Path, spec: dict) -> Path:
    path = tmp_path / "sweep.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False), encoding="utf-8")
    return path


def index(out: Path) -> dict[str, dict]:
    return {cell["name"]: cell for cell in json.loads((out / "sweep.json").read_text())["cells"]}


def planned_trials(path: Path, out: Path) -> dict[str, int]:
    return {c.name: len(planned_evaluation(c.config).plan) for c in sweep_cells(path, read_sweep_file(path), out)}


def assert_whole(path: Path, out: Path) -> None:
    """Every cell complete, its journal holding each planned trial exactly once, in order."""
    for name, planned in planned_trials(path, out).items():
        records = read_journal(out / name / "journal.jsonl")
        assert [r.index for r in records] == list(range(planned)), name
        assert json.loads((out / name / "summary.json").read_text())["complete"] is True


def running_cells() -> dict[str, int]:
    """This test session's worker processes running a sweep cell, by cell name (Ray titles them `ray::cell NAME`).
    The module's Ray was started here, so its workers descend from this process; other sweeps on the machine do not."""
    found = {}
    for proc in psutil.Process().children(recursive=True):
        try:
            title = proc.cmdline()[0] if proc.cmdline() else ""
        except psutil.Error:
            continue
        if title.startswith("ray::cell "):
            found[title.removeprefix("ray::cell ")] = proc.pid
    return found


# How long to wait for a sweep to get going: Ray starting its workers and each cell importing LeRobot and torch, on a
# 2-core CI machine whose other core runs the rest of the suite (60 s was once too short there). Not a speed promise.
def wait_for(condition, timeout: float = 180.0) -> None:
    end = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < end, "timed out"
        time.sleep(0.05)


def trials_recorded(run_dir: Path) -> int:
    journal = run_dir / "journal.jsonl"
    return journal.read_bytes().count(b"\n") if journal.exists() else 0


def test_a_sweep_runs_every_cell_once_gathers_results_and_reports_a_bad_cell_in_one_line(local_ray, tmp_path, capsys):
    empty = tmp_path / "empty_policy"  # no policy in it: it passes the sweep's up-front checks and fails in its cells
    empty.mkdir()
    with_broken = [*SMALL["cells"], {"name": "broken", "policy": {"path": str(empty)}}]
    path, out = write(tmp_path, {**SMALL, "cells": with_broken}), tmp_path / "out"
    assert main([str(path), f"--output_dir={out}"]) == 1
    lines = capsys.readouterr().out.splitlines()
    for seed in (0, 1):
        failed = f"broken,seed={seed}: failed: --policy.path: cannot load a LeRobot policy config from '{empty}'"
        assert any(line.startswith(failed) for line in lines), lines
    assert sum("broken" in line for line in lines) == 2
    assert lines[-1] == f"sweep: 4 of 6 cells complete, 2 failed; results: {out / 'results.parquet'}"
    cells = index(out)
    good = [name for name in cells if not name.startswith("broken")]
    assert all(cells[name]["status"] == "complete" for name in good) and len(good) == 4
    results = pd.read_parquet(out / "results.parquet")
    assert set(results["cell"]) == set(good)
    assert {"seed", "strategy", "perturbations", "cell_status", "spl", "cost"} <= set(results.columns)
    assert results.groupby("cell").size().to_dict() == {n: len(read_journal(out / n / "journal.jsonl")) for n in good}
    assert set(results.loc[results["cell"] == "lb,seed=1", "perturbations"]) == {"LB1+LB2"}

    assert report_main([str(out)]) == 0
    report = (out / "report" / "report.md").read_text()
    assert "standard (pooled)" in report and "contrast ΔLB1+ΔLB2 (pooled)" in report

    assert main([str(path), f"--output_dir={out}"]) == 2
    assert "pass --resume=true to continue it" in capsys.readouterr().err
    journals = {name: (out / name / "journal.jsonl").read_bytes() for name in good}
    assert main([str(path), f"--output_dir={out}", "--resume=true"]) == 1
    assert "4 of 6 cells already complete" in capsys.readouterr().out
    assert journals == {name: (out / name / "journal.jsonl").read_bytes() for name in good}


def test_a_learned_policy_loads_once_per_worker_not_once_per_cell(local_ray, tmp_path):
    spec = {"eval": {"n_instances": 1, "max_episode_steps": 3, "rerun": False}, "grid": {"seed": [0, 1, 2, 3]}}
    out = tmp_path / "out"
    assert main([str(write(tmp_path, spec)), f"--output_dir={out}"]) == 0
    cells = index(out).values()
    workers = {cell["pid"] for cell in cells}
    assert sum(cell["policy_loaded"] for cell in cells) == len(workers) < len(cells)


# Ray starts a worker process of its own for GPU tasks, which imports LeRobot and torch afresh: one GPU cell only.
@pytest.mark.slow
def test_a_cell_on_cuda_gets_its_share_of_the_gpu_from_ray_and_a_cell_on_the_cpu_none(local_ray, tmp_path):
    cells = [{"name": "gpu", "policy.device": "cuda"}, {"name": "cpu"}]
    spec = {"eval": {"n_instances": 1, "strategy": "standard", **ORACLE, "max_episode_steps": 5}, "cells": cells}
    out = tmp_path / "out"
    assert main([str(write(tmp_path, spec)), f"--output_dir={out}", "--ray.gpus_per_cell=0.5"]) == 0
    cells = index(out)
    assert {name: (cell["gpus"], cell["cuda_visible_devices"]) for name, cell in cells.items()} == {
        "gpu": (0.5, "0"),
        "cpu": (0.0, None),
    }


@pytest.mark.slow
def test_a_worker_killed_mid_cell_is_retried_and_resumes_from_its_journal(local_ray, tmp_path):
    path, out = write(tmp_path, LONG), tmp_path / "out"
    codes = []
    sweep = threading.Thread(target=lambda: codes.append(main([str(path), f"--output_dir={out}"])))
    sweep.start()
    wait_for(lambda: trials_recorded(out / "seed=0") >= 2 and "seed=0" in running_cells())
    victim = running_cells()["seed=0"]
    before = (out / "seed=0" / "journal.jsonl").read_bytes()
    os.kill(victim, signal.SIGKILL)
    sweep.join(timeout=300)
    assert codes == [0]
    assert_whole(path, out)
    after = (out / "seed=0" / "journal.jsonl").read_bytes()
    assert after.startswith(before[: before.rfind(b"\n") + 1])  # resumed: the recorded trials were kept
    assert index(out)["seed=0"]["pid"] != victim


@pytest.mark.slow
def test_a_killed_sweep_resumes_its_unfinished_cells(local_ray, tmp_path):
    path, out = write(tmp_path, LONG), tmp_path / "out"
    command = [sys.executable, "-m", "lerobot_contrast.sweep", str(path), f"--output_dir={out}"]
    driver = subprocess.Popen([*command, f"--ray.address={local_ray}"], stdout=subprocess.DEVNULL)
    wait_for(lambda: trials_recorded(out / "seed=0") >= 2)
    driver.kill()
    driver.wait()
    wait_for(lambda: not running_cells())  # Ray ends the dead driver's tasks
    journals = {name: out / name / "journal.jsonl" for name in ("seed=0", "seed=1", "seed=2")}
    started = {name: journal.read_bytes() if journal.exists() else b"" for name, journal in journals.items()}
    assert main([str(path), f"--output_dir={out}", "--resume=true"]) == 0
    assert_whole(path, out)
    for name, before in started.items():
        assert journals[name].read_bytes().startswith(before[: before.rfind(b"\n") + 1])
