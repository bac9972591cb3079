"""Fault injection end to end: the evaluation SIGKILLed at chosen moments (each run a process of its own, forked
from one that has imported it: tests/fault_moments.py) and resumed, two writers on one run directory, and a full
disk. Under every fault nothing is lost or duplicated, and the resumed run equals an uninterrupted one, its
LeRobotDataset and Rerun files included."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from lerobot.datasets import LeRobotDataset

from tests import fault_moments

ARGS = ["--n_instances=5", "--seed=3", "--policy.type=oracle", "--record_dataset=true"]
VARYING = ("duration_s", "started_at", "wall_time_s")  # the clock's, not the run's


def cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "lerobot_contrast.eval", *args], capture_output=True, text=True, timeout=300
    )


def resumed_here(run: Path, capsys) -> tuple[int, str, str]:
    """Resume the run in this process: the same main as the command, reading what the killed process left on disk,
    without another interpreter loading torch and LeRobot (seconds a resume). Its exit code, stdout and stderr."""
    from lerobot_contrast.eval import main

    capsys.readouterr()
    code = main([*ARGS, f"--output_dir={run}", "--resume=true"])
    said = capsys.readouterr()
    return code, said.out, said.err


def killed_at(moment: str, at: int, run: Path, *flags: str, **env: str) -> fault_moments.Run:
    """The evaluation into `run`, in a process of its own that `moment` kills (tests/fault_moments.py)."""
    return fault_moments.start(moment, at, [*ARGS, f"--output_dir={run}", *flags], run.parent / "forked", env)


def journal(run: Path) -> list[dict]:
    lines = (run / "journal.jsonl").read_text().splitlines()
    return [{k: v for k, v in json.loads(line).items() if k not in VARYING} for line in lines]


def results(run: Path) -> list[dict]:
    return [
        {k: v for k, v in row.items() if k not in VARYING} for row in pq.read_table(run / "results.parquet").to_pylist()
    ]


def summary(run: Path) -> dict:
    data = json.loads((run / "summary.json").read_text())
    data["overall"].pop("wall_time_s")
    return data


def frames(run: Path) -> list[dict]:
    """Every frame of the run's dataset, without its images (the same frames encode to the same columns)."""
    dataset = LeRobotDataset("local/run", root=run / "dataset")
    columns = [name for name in dataset.hf_dataset.column_names if name not in dataset.meta.video_keys]
    return dataset.hf_dataset.select_columns(columns).to_list()


def leftovers(run: Path) -> list[str]:
    return sorted(p.name for p in run.rglob("*") if p.name.endswith((".tmp", ".partial")))


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    run = tmp_path_factory.mktemp("reference") / "run"
    result = cli(*ARGS, f"--output_dir={run}")
    assert result.returncode == 0, result.stderr
    return run


def assert_same_run(run: Path, reference: Path) -> None:
    """Nothing lost, nothing duplicated, and the same results, dataset and Rerun files as the uninterrupted run."""
    assert journal(run) == journal(reference)
    assert results(run) == results(reference) and summary(run) == summary(reference)
    assert frames(run) == frames(reference)
    rrd = sorted(p.name for p in (run / "rerun").iterdir())
    assert rrd == sorted(p.name for p in (reference / "rerun").iterdir())
    assert leftovers(run) == []


KILLS = {
    "the first episode counted in info.json": [("dataset_counted", 1)],
    "three later episodes counted in info.json": [
        ("dataset_counted", 3),
        ("dataset_counted", 6),
        ("dataset_counted", 9),
    ],
    "an episode saved, its trial not journaled": [("episode_saved", 2)],
    "a journal line appended, then one torn": [("journal_appended", 4), ("journal_torn", 20)],
    "the final write of results.parquet": [("final_write", 0)],
}


@pytest.mark.slow
@pytest.mark.parametrize("case", KILLS)
def test_a_run_killed_at_any_moment_resumes_to_the_uninterrupted_run(tmp_path, reference, case, capsys):
    run, resume = tmp_path / "run", ()
    for moment, at in KILLS[case]:
        code, _, err = killed_at(moment, at, run, *resume).wait()
        assert code == -9, err[-3000:]
        resume = ("--resume=true",)
    code, out, err = resumed_here(run, capsys)
    assert code == 0, err[-3000:]
    assert_same_run(run, reference)
    if ("journal_torn", 20) in KILLS[case]:
        assert "dropped its last line, cut off mid-write by a kill; that trial runs again" in out


@pytest.mark.slow
def test_a_second_writer_is_refused_naming_the_first(tmp_path, reference, capsys):
    run, marker = tmp_path / "run", tmp_path / "holding"
    assert killed_at("journal_appended", 10, run).wait()[0] == -9
    first = killed_at("hold_after_append", 20, run, "--resume=true", FAULT_MARKER=str(marker))
    deadline = time.monotonic() + 120
    while not marker.exists() and first.process.is_alive() and time.monotonic() < deadline:
        time.sleep(0.05)
    code, _, err = resumed_here(run, capsys)  # the second writer
    marker.unlink()
    first_code, _, first_err = first.wait()
    assert code == 2 and err.count("\n") == 1, err
    assert f"is in use by process {first.pid} (an evaluation, since " in err
    assert first_code == 0, first_err[-3000:]
    assert_same_run(run, reference)


@pytest.mark.slow
def test_a_full_disk_is_one_line_and_the_run_resumes_once_there_is_room(tmp_path, reference, capsys):
    run = tmp_path / "run"
    code, _, err = killed_at("disk_full", 12, run).wait()
    assert code == 2 and err.count("\n") == 1, err[-3000:]
    assert f"error: no space left on the disk holding {run}; free space and resume with --output_dir={run} " in err
    assert leftovers(run) == [] and len(journal(run)) == 12
    code, _, err = resumed_here(run, capsys)
    assert code == 0, err[-3000:]
    assert_same_run(run, reference)


# Each size fills up at another point: config and plan, the first Rerun file, a dataset episode, later episodes.
DISK_SIZES = ("16k", "200k", "600k", "1200k")
# Run in a mount namespace of its own: a tmpfs of the given size, the evaluation onto it (stopped by the full disk),
# then the disk given room and the run resumed. Each run is a process of its own, forked from this one once it has
# imported eval (not another interpreter loading torch and LeRobot); what each said and its exit code go to OUT.
ON_A_SMALL_DISK = """
import os, subprocess, sys, traceback
from pathlib import Path
import lerobot_contrast.record.dataset, rerun, torch  # what every run loads, loaded once
from lerobot_contrast.eval import main

size, disk, out, args = sys.argv[1], Path(sys.argv[2]), Path(sys.argv[3]), sys.argv[4:]
if subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(disk)]).returncode:
    sys.exit(99)

def run(name, *flags):
    pid = os.fork()
    if pid == 0:
        code = 1
        try:
            for fd, suffix in ((1, "out"), (2, "err")):
                os.dup2(os.open(out / f"{name}.{suffix}", os.O_WRONLY | os.O_CREAT | os.O_TRUNC), fd)
            code = main([*args, f"--output_dir={disk / 'run'}", *flags])
        except BaseException:
            traceback.print_exc()
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(code)
    (out / f"{name}.rc").write_text(f"{os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1])}\\n")

run("first")
leftovers = sorted(str(p) for p in disk.rglob("*") if p.name.endswith((".tmp", ".partial")))
(out / "leftovers").write_text("".join(f"{p}\\n" for p in leftovers))
subprocess.run(["mount", "-o", "remount,size=512m", str(disk)], check=True)
run("again", "--resume=true" if (disk / "run").is_dir() else "--resume=false")
subprocess.run(["cp", "-a", str(disk / "run"), str(out / "run")], check=True)
"""


def small_disks_mount() -> bool:
    """Whether this machine lets an unprivileged mount namespace mount a tmpfs (else the hook test stands in)."""
    if shutil.which("unshare") is None:
        return False
    probe = subprocess.run(["unshare", "-rm", "sh", "-c", "mount -t tmpfs tmpfs /mnt"], capture_output=True)
    return probe.returncode == 0


@pytest.mark.slow
@pytest.mark.skipif(not small_disks_mount(), reason="no tmpfs mounts in an unprivileged namespace here")
@pytest.mark.parametrize("size", DISK_SIZES)
def test_a_run_on_a_small_disk_stops_in_one_line_and_completes_when_given_room(tmp_path, reference, size):
    disk, out = tmp_path / "disk", tmp_path / "out"
    disk.mkdir()
    out.mkdir()
    command = ["unshare", "-rm", sys.executable, "-c", ON_A_SMALL_DISK, size, str(disk), str(out), *ARGS]
    subprocess.run(command, check=True, timeout=600)
    first, again = (out / "first.err").read_text(), (out / "again.err").read_text()
    assert (out / "first.rc").read_text().strip() == "2" and first.count("\n") == 1, first[-3000:]
    assert first.startswith(f"error: no space left on the disk holding {disk / 'run'}; free space and ")
    assert (out / "leftovers").read_text() == ""
    assert (out / "again.rc").read_text().strip() == "0", again[-3000:]
    assert_same_run(out / "run", reference)


def delete(path: Path) -> None:
    if path.is_dir():
        shutil.rmtree(path)
    else:
        path.unlink()


def truncate(path: Path) -> None:
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])


def files(run: Path) -> dict[str, bytes]:
    """Every file of the run but its lock, which each writer stamps with its process."""
    return {
        p.relative_to(run).as_posix(): p.read_bytes()
        for p in sorted(run.rglob("*"))
        if p.is_file() and p.name != ".lock"
    }


# (what is damaged, how, the file the refusal names, what it says of it)
DATASET_DAMAGE = {
    "a deleted data parquet": ("dataset/data/chunk-000/file-002.parquet", delete, "", "is missing"),
    "the data folder deleted": ("dataset/data", delete, "/chunk-000/file-000.parquet", "is missing"),
    "a truncated data parquet": ("dataset/data/chunk-000/file-004.parquet", truncate, "", "is damaged"),
    "a deleted video file": ("dataset/videos/*/chunk-000/file-003.mp4", delete, "", "is missing"),
    "a truncated video file": ("dataset/videos/*/chunk-000/file-001.mp4", truncate, "", "is damaged"),
    "a truncated episodes metadata file": (
        "dataset/meta/episodes/chunk-000/file-002.parquet",
        truncate,
        "",
        "is damaged",
    ),
}


@pytest.mark.slow
@pytest.mark.parametrize("case", DATASET_DAMAGE)
def test_a_resume_refuses_a_dataset_that_lacks_what_the_journal_names_naming_the_file(
    tmp_path, reference, case, capsys
):
    pattern, damage, named, said = DATASET_DAMAGE[case]
    run = tmp_path / "run"
    shutil.copytree(reference, run)
    (target,) = run.glob(pattern)
    damage(target)
    before = files(run)
    code, _, err = resumed_here(run, capsys)
    assert code == 2 and err.count("\n") == 1, err[-3000:]
    assert err.startswith(f"error: {target}{named} {said}"), err
    assert "; restore it from a copy and resume, or run the evaluation again into a new --output_dir" in err
    assert files(run) == before


@pytest.mark.slow
def test_a_resume_refuses_a_deleted_dataset_the_journal_names(tmp_path, reference, capsys):
    run = tmp_path / "run"
    shutil.copytree(reference, run)
    shutil.rmtree(run / "dataset")
    code, _, err = resumed_here(run, capsys)
    assert code == 2 and err.count("\n") == 1, err[-3000:]
    assert err.startswith(f"error: {run / 'dataset'} is missing, but the journal names "), err
    assert not (run / "dataset").exists()
