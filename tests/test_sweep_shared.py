"""Episodes shared between a sweep's cells (share_episodes: true): every cell's journal is the one it writes without
sharing, the cells that stage an instance another cell ran take its episode, and only policies whose episodes
the instance decides share. The cells run in this process, as a Ray worker runs them."""

import json
from pathlib import Path

import pytest
import yaml

from lerobot_contrast.record.shared_episodes import FOLDER
from lerobot_contrast.sweep.cells import SweepFileError, read_sweep_file, sharing_predecessors, sweep_cells
from lerobot_contrast.sweep.worker import run_cell

WALL_CLOCK = ("started_at", "duration_s")
STUDY = {
    "eval": {"n_instances": 3, "max_episode_steps": 12, "rerun": False},
    "grid": {"seed": [4]},
    # Longest first, as the paper's study: the standard cell finds every episode it stages already run.
    "cells": [
        {"name": "contrast_all4", "strategy": "contrast", "perturbations": ["LB1", "LB2", "SB1", "SB2"]},
        {"name": "contrast_lb", "strategy": "contrast", "perturbations": ["LB1", "LB2"]},
        {"name": "standard", "strategy": "standard"},
    ],
}


def run_study(tmp_path: Path, spec: dict, name: str) -> Path:
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False), encoding="utf-8")
    out = tmp_path / name
    for cell in sweep_cells(path, read_sweep_file(path), out):
        assert run_cell(cell.name, cell.config, cell.shared).status == "complete"
    return out


def journals(out: Path) -> dict[str, list[dict]]:
    runs = sorted(p.parent for p in out.glob("*/journal.jsonl"))
    return {
        run.name: [{k: v for k, v in json.loads(line).items() if k not in WALL_CLOCK} for line in
                   (run / "journal.jsonl").read_text().splitlines()]
        for run in runs
    }  # fmt: skip


@pytest.mark.slow
def test_cells_sharing_episodes_write_the_journals_they_write_alone_and_run_repeated_instances_once(tmp_path):
    alone = journals(run_study(tmp_path, STUDY, "alone"))
    shared_out = run_study(tmp_path, {**STUDY, "share_episodes": True}, "shared")
    assert journals(shared_out) == alone
    staged = [r for records in alone.values() for r in records if r["status"] in ("done", "aborted")]
    distinct = {json.dumps(r["instance"], sort_keys=True) for r in staged}
    ran = list((shared_out / FOLDER).glob("*/*.pkl"))
    # Each distinct instance ran once; the originals the contrast cells share with the standard cell were taken.
    assert len(ran) == len(distinct) < len(staged)
    assert not list((shared_out / FOLDER).glob("*/*.part"))


@pytest.mark.slow
def test_the_apartments_cells_share_episodes_with_the_journals_they_write_alone(tmp_path):
    apartment = {
        "eval": {"task": "vln", "n_instances": 2, "max_episode_steps": 10, "rerun": False,
                 "robot": {"type": "vln_sim", "camera_width": 160, "camera_height": 120}},
        "grid": {"seed": [1]},
        "cells": [
            {"name": "contrast_all4", "strategy": "contrast", "perturbations": ["L", "LB", "S", "SB"]},
            {"name": "standard_reset", "strategy": "standard", "cost": "reset_time"},
        ],
    }  # fmt: skip
    alone = journals(run_study(tmp_path, apartment, "alone"))
    shared_out = run_study(tmp_path, {**apartment, "share_episodes": True}, "shared")
    assert journals(shared_out) == alone
    staged = [r for records in alone.values() for r in records if r["status"] in ("done", "aborted")]
    assert len(list((shared_out / FOLDER).glob("*/*.pkl"))) < len(staged)


def test_a_policy_that_draws_from_the_trials_randomness_shares_nothing(tmp_path):
    oracle = {**STUDY, "share_episodes": True, "cells": STUDY["cells"][-1:]}
    oracle["eval"] = {**STUDY["eval"], "n_instances": 2, "max_episode_steps": 5, "policy": {"type": "oracle"}}
    out = run_study(tmp_path, oracle, "oracle")
    assert (out / "standard,seed=4" / "journal.jsonl").is_file()
    assert not (out / FOLDER).exists()


def test_cells_that_would_share_episodes_run_one_after_another_and_the_rest_at_once(tmp_path):
    spec = {**STUDY, "grid": {"seed": [4, 5]}}
    spec["cells"] = [*STUDY["cells"], {"name": "other_policy", "strategy": "standard", "policy": {"type": "oracle"}}]
    path = tmp_path / "study.yaml"
    path.write_text(yaml.safe_dump({**spec, "share_episodes": True}), encoding="utf-8")
    after = sharing_predecessors(sweep_cells(path, read_sweep_file(path), tmp_path / "out"))
    # Per seed, each cell of the same policy waits for the one before it in the file; seeds and policies apart.
    assert after == {
        "contrast_all4,seed=4": None, "contrast_all4,seed=5": None,
        "contrast_lb,seed=4": "contrast_all4,seed=4", "contrast_lb,seed=5": "contrast_all4,seed=5",
        "standard,seed=4": "contrast_lb,seed=4", "standard,seed=5": "contrast_lb,seed=5",
        "other_policy,seed=4": None, "other_policy,seed=5": None,
    }  # fmt: skip
    path.write_text(yaml.safe_dump(spec), encoding="utf-8")
    assert set(sharing_predecessors(sweep_cells(path, read_sweep_file(path), tmp_path / "out")).values()) == {None}


def test_share_episodes_takes_true_or_false_in_one_line(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump({**STUDY, "share_episodes": "yes"}), encoding="utf-8")
    with pytest.raises(SweepFileError, match=r"share_episodes must be true or false, got 'yes'$"):
        sweep_cells(path, read_sweep_file(path), tmp_path / "out")


def test_weights_retrained_at_the_same_path_share_no_episodes_with_the_old_ones():
    torch = pytest.importorskip("torch")
    from lerobot_contrast.record.shared_episodes import weights_digest

    net = torch.nn.Linear(3, 2)
    before = weights_digest(net)
    assert weights_digest(net) == before
    with torch.no_grad():
        net.bias[0] += 1e-6
    assert weights_digest(net) != before
