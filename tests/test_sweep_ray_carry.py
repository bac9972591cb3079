"""What travels between the driver and a cluster's nodes (no Ray needed): run directories between a node's own disk and
the sweep folder (what comes back, what a node resumes from, how a node tells it shares the folder), this project's
code, and a policy folder a node does not have."""

import tempfile
from pathlib import Path

import pytest

from lerobot_contrast.spine.config import EvalConfig
from lerobot_contrast.sweep.carry import Carry, journal_lines, local_run_dir, mark_folder, pack, unpack
from lerobot_contrast.sweep.shipping import shipped_paths
from lerobot_contrast.sweep.worker import run_cell

FILES = ("config.json", "plan.json", "journal.jsonl", "results.parquet", "summary.json")


def run_dir(path: Path, trials: int = 2) -> Path:
    path.mkdir(parents=True)
    for name in FILES:
        (path / name).write_text("x\n" * trials if name == "journal.jsonl" else name)
    (path / "rerun").mkdir()
    (path / "rerun" / "episode_000000.rrd").write_bytes(b"rrd")
    (path / "dataset" / "data").mkdir(parents=True)
    (path / "dataset" / "data" / "chunk.parquet").write_bytes(b"pq")
    (path / ".lock").write_text("pid 1")
    return path


def tree(path: Path) -> set[str]:
    return {p.relative_to(path).as_posix() for p in path.rglob("*") if p.is_file()}


def test_a_run_directory_comes_back_whole_with_or_without_its_recordings_and_never_its_lock(tmp_path):
    source = run_dir(tmp_path / "node" / "cell")
    unpack(pack(source), tmp_path / "sweep" / "cell")
    assert tree(tmp_path / "sweep" / "cell") == tree(source) - {".lock"}
    assert (tmp_path / "sweep" / "cell" / "rerun" / "episode_000000.rrd").read_bytes() == b"rrd"
    unpack(pack(source, recordings=False), tmp_path / "lean" / "cell")
    assert tree(tmp_path / "lean" / "cell") == set(FILES)


def test_a_returning_run_directory_replaces_the_old_copy_and_leaves_nothing_beside_it(tmp_path):
    target = run_dir(tmp_path / "sweep" / "cell", trials=1)
    (target / "stale.txt").write_text("from an older attempt")
    unpack(pack(run_dir(tmp_path / "node" / "cell", trials=3)), target)
    assert journal_lines(target) == 3 and not (target / "stale.txt").exists()
    assert [p.name for p in target.parent.iterdir()] == ["cell"]


def test_a_node_resumes_from_whichever_copy_holds_more_trials(tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "node_tmp"))
    driver = run_dir(tmp_path / "sweep" / "cell", trials=2)
    carry = Carry("abc", tmp_path / "sweep", pack(driver))
    assert journal_lines(local_run_dir(carry, "cell")) == 2  # nothing on the node yet: the driver's copy
    local = carry.local_root() / "cell"
    (local / "journal.jsonl").write_text("x\n" * 5)  # the node ran on after the driver was killed
    assert journal_lines(local_run_dir(carry, "cell")) == 5
    ahead = Carry("abc", tmp_path / "sweep", pack(run_dir(tmp_path / "later" / "cell", trials=7)))
    assert journal_lines(local_run_dir(ahead, "cell")) == 7
    assert journal_lines(local_run_dir(Carry("abc", tmp_path / "sweep"), "fresh")) == 0


def test_a_node_shares_the_sweep_folder_only_where_it_reads_the_sweeps_own_id_there(tmp_path):
    folder = tmp_path / "sweep"
    folder.mkdir()
    sweep_id = mark_folder(folder)
    assert mark_folder(folder) == sweep_id  # a resumed sweep keeps its id, so its nodes find their copies
    assert Carry(sweep_id, folder).shares_folder()
    assert not Carry("another sweep", folder).shares_folder()
    assert not Carry(sweep_id, tmp_path / "not_mounted_here").shares_folder()


@pytest.mark.parametrize("path", ["/nowhere/pretrained_model", "./outputs/train/a"])
def test_a_policy_folder_missing_on_the_node_fails_its_cell_in_one_line(tmp_path, monkeypatch, path):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "node_tmp"))
    cfg = EvalConfig(output_dir=tmp_path / "sweep" / "cell")
    cfg.policy.path = path
    outcome = run_cell("cell", cfg, None, Carry("abc", tmp_path / "sweep"))
    assert outcome.status == "failed" and outcome.run_dir is None
    assert outcome.error == (
        f"policy.path {path} is not on this machine: a checkpoint folder must be at that path on every node "
        "(storage they all mount there), or on the Hub (give its repo id)"
    )


def test_the_code_a_cluster_receives_is_each_project_package_with_its_metadata():
    paths = shipped_paths()
    packages = {p.name for p in paths if not p.name.endswith(".dist-info")}
    assert {"lerobot_contrast", "lerobot_policy_tabletop_pointer", "lerobot_robot_locobot"} <= packages
    for package in packages:  # its metadata beside it: entry points and LeRobot's plugin discovery on the node
        (metadata,) = [p for p in paths if p.name.startswith(f"{package}-") and p.name.endswith(".dist-info")]
        assert (metadata / "METADATA").is_file()
    contrast = next(p for p in paths if p.name == "lerobot_contrast")
    assert (contrast / "sweep" / "worker.py").is_file()
    metadata = next(p for p in paths if p.name.startswith("lerobot_contrast-"))
    assert "lerobot_contrast.tasks" in (metadata / "entry_points.txt").read_text()
