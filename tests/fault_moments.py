"""The moments the fault tests kill an evaluation at (test-side only: the product has no such hook), and killed runs
forked from one process that has imported the evaluation's libraries already, so that each costs its trials and not
another interpreter loading torch and LeRobot."""

from __future__ import annotations

import json
import multiprocessing
import os
import signal
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

# Imported in the fork server once, then shared by every run forked from it.
PRELOAD = ["tests.fault_moments", "lerobot_contrast.eval", "lerobot_contrast.record.dataset", "torch"]


def kill() -> None:
    os.kill(os.getpid(), signal.SIGKILL)


def hold() -> None:
    """Say so, then wait for the test to let the run go on."""
    marker = Path(os.environ["FAULT_MARKER"])
    marker.touch()
    while marker.exists():
        time.sleep(0.05)


def after(owner: object, name: str, strikes: Callable, then: Callable[[], None] = kill) -> None:
    real = getattr(owner, name)

    def patched(*args, **kwargs):
        result = real(*args, **kwargs)
        if strikes(args, result):
            then()
        return result

    setattr(owner, name, patched)


def strike(moment: str, at: int) -> None:
    """Patch this process so that the run dies (or holds, or finds the disk full) at `moment`, trial or episode `at`."""
    import lerobot.datasets.dataset_metadata as metadata
    import pyarrow.parquet as pq

    import lerobot_contrast.record.journal as journal
    from lerobot_contrast.record.dataset import DatasetRecorder

    real_append = journal._append_line

    def torn(path, data):  # half a line reaches the disk
        if json.loads(data)["index"] != at:
            return real_append(path, data)
        real_append(path, data[: len(data) // 2])
        kill()

    def full(path, data):  # the disk fills up as the journal line is written
        if json.loads(data)["index"] == at:
            raise OSError(28, os.strerror(28))
        return real_append(path, data)

    if moment == "dataset_counted":  # info.json counts the episode; its metadata and journal line are not written
        after(metadata, "write_info", lambda args, _: args[0].total_episodes == at)
    elif moment == "episode_saved":  # the episode is finalized; its trial's journal line is not written
        after(DatasetRecorder, "end", lambda args, files: files.dataset_episode == at)
    elif moment == "journal_appended":
        after(journal.Journal, "append", lambda args, _: args[1].index == at)
    elif moment == "journal_torn":
        journal._append_line = torn
    elif moment == "final_write":  # results.parquet is being written after the last trial
        after(pq, "write_table", lambda args, _: str(args[1]).endswith("results.parquet.tmp"))
    elif moment == "disk_full":
        journal._append_line = full
    elif moment == "hold_after_append":
        after(journal.Journal, "append", lambda args, _: args[1].index == at, then=hold)
    else:
        raise ValueError(f"no such moment: {moment}")


def _run(moment: str, at: int, argv: list[str], out: str, err: str, env: dict[str, str]) -> None:
    os.environ.update(env)
    for fd, path in ((1, out), (2, err)):
        os.dup2(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC), fd)
    from lerobot_contrast.eval import main

    strike(moment, at)
    code = main(argv)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


@dataclass
class Run:
    """A forked run: its process, and what it wrote."""

    process: multiprocessing.process.BaseProcess
    out: Path
    err: Path

    @property
    def pid(self) -> int:
        return self.process.pid

    def wait(self, timeout: float = 300) -> tuple[int, str, str]:
        """Its exit code (-9: killed), stdout and stderr."""
        self.process.join(timeout)
        assert self.process.exitcode is not None, "the run did not end in time"
        return self.process.exitcode, self.out.read_text(), self.err.read_text()


def start(moment: str, at: int, argv: list[str], folder: Path, env: dict[str, str] | None = None) -> Run:
    """Fork eval's main with `moment` armed, its output going to files in `folder`."""
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(PRELOAD)
    folder.mkdir(parents=True, exist_ok=True)
    out, err = folder / f"{moment}_{at}.out", folder / f"{moment}_{at}.err"
    process = context.Process(target=_run, args=(moment, at, argv, str(out), str(err), env or {}))
    process.start()
    return Run(process, out, err)
