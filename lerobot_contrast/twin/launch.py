"""Starting the virtual SO-101 (`python -m lerobot_contrast.twin`) as a child process and reading the endpoints it
prints, for the recording script, the benchmark and the tests."""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import subprocess
import sys
import tempfile
import typing
from collections.abc import Iterator
from dataclasses import dataclass

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.ports import free_port

ENDPOINTS = ("bus", "camera", "placement", "calibration", "clock", "eval flags")
PR_SET_PDEATHSIG = 1  # Linux's prctl option: a signal for this process when its parent dies
PARENT = "LEROBOT_CONTRAST_TWIN_PARENT"  # the environment variable naming the process that started the twin


def stop_with_parent() -> None:
    """Called first in a twin that `start_twin` started (Linux): ask for a SIGTERM when the process that started it
    dies, even killed (a benchmark killed with -9 left its twin running, holding its ports and a core); where that
    process is already gone, stop now. Asked by the twin itself, not between fork and exec, where only
    async-signal-safe calls belong."""
    parent = os.environ.get(PARENT)
    if parent is None or sys.platform != "linux":
        return
    ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)
    if os.getppid() != int(parent):
        raise SystemExit("the process that started the twin is gone")


@dataclass
class RunningTwin:
    process: subprocess.Popen
    endpoints: dict[str, str]
    log: typing.IO[str]

    @property
    def port(self) -> str:
        return self.endpoints["bus"].split()[0]

    @property
    def placement(self) -> str:
        return self.endpoints["placement"].split()[0]

    @property
    def robot_flags(self) -> str:
        """The `--robot.*` flags the twin printed, for LeRobot's commands."""
        return self.endpoints["eval flags"]

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
        try:
            self.process.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.communicate()
        self.log.close()


def start_twin(*flags: str) -> RunningTwin:
    """Start the twin with `flags` and wait for its endpoints; a twin that cannot start is one line saying why."""
    # A file, not a pipe: nobody reads the twin's log while it runs. Closed when the twin stops.
    log = tempfile.TemporaryFile("w+")  # noqa: SIM115
    process = subprocess.Popen(
        [sys.executable, "-m", "lerobot_contrast.twin", *flags],
        stdout=subprocess.PIPE,
        stderr=log,
        text=True,
        env={**os.environ, PARENT: str(os.getpid())},
    )
    endpoints = {}
    for _ in ENDPOINTS:
        line = process.stdout.readline()
        if not line:
            process.wait()
            log.seek(0)
            error = log.read().strip().splitlines()
            log.close()
            raise UserError(f"the twin did not start: {error[-1] if error else 'no output'}")
        key, _, value = line.partition(": ")
        endpoints[key] = value.strip()
    return RunningTwin(process, endpoints, log)


@contextlib.contextmanager
def running_twin(*flags: str) -> Iterator[RunningTwin]:
    """A twin started with `flags` on free ports, with a calibration folder of its own, stopped on leaving; a twin
    that cannot start is a UserError of one line."""
    with tempfile.TemporaryDirectory() as calibration:
        twin = start_twin(f"--calibration_dir={calibration}", f"--camera_port={free_port()}",
                          f"--control_port={free_port()}", f"--clock_port={free_port()}", *flags)  # fmt: skip
        try:
            yield twin
        finally:
            twin.stop()
