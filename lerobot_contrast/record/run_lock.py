"""The run directory's lock (`.lock`): one writer at a time. It is an OS file lock, so the kernel releases it when
its process ends, however it ends; the file itself stays and names the last holder."""

from __future__ import annotations

import fcntl
import os
from datetime import datetime
from pathlib import Path

from lerobot_contrast.contrast.errors import UserError

LOCK_FILE = ".lock"


class RunLockedError(UserError):
    pass


class RunLock:
    """An exclusive lock on a run directory, held from `acquire` until `release` or the end of the process."""

    def __init__(self, path: Path, fd: int) -> None:
        self.path = path
        self._fd: int | None = fd

    @classmethod
    def acquire(cls, run_dir: Path, holder: str) -> RunLock:
        """Lock `run_dir` for `holder` (what this process does there), or refuse naming the process that holds it."""
        path = run_dir / LOCK_FILE
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            other = os.pread(fd, 4096, 0).decode("utf-8", "replace").strip()
            os.close(fd)
            raise RunLockedError(
                f"{run_dir} is in use by {other or 'another process'}; wait until it ends, or stop it, and run again"
            ) from None
        started = datetime.now().strftime("%Y-%m-%d %H:%M:%S")
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"process {os.getpid()} ({holder}, since {started})\n".encode(), 0)
        return cls(path, fd)

    def release(self) -> None:
        # The file stays: unlinking it would let a waiting writer lock a file the next one no longer sees.
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None
