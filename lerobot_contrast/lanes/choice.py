"""How many lanes and torch threads an evaluation runs with: lanes are its parallelism, so torch gets one thread,
chosen rather than inherited (results then do not depend on the core count, and a busy machine slows it in proportion
to the share it leaves, instead of stalling threads that wait on each other)."""

from __future__ import annotations

import os
from contextlib import suppress
from typing import Any

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.lanes.seats import batches_lanes

# Lanes `--lanes=auto` runs on our simulators: scripts/bench/bench_lanes.py measures their speed and memory.
AUTO_LANES = 8
EVAL_THREADS = 1


class LanesError(UserError):
    pass


def parse_lanes(value: str | int) -> int | None:
    """--lanes: a whole number >= 1, or auto (None)."""
    text = str(value).strip().lower()
    if text == "auto":
        return None
    if not text.isdigit() or int(text) < 1:
        raise LanesError(f"--lanes must be auto or a whole number >= 1, got {value!r}")
    return int(text)


def choose_lanes(
    value: str | int, robot: Any, policy: Any, *, operator: bool, fps: float | None, max_episode_s: float | None = None
) -> int:
    """The lanes to run: one on hardware, with an operator, at a fixed rate or with episodes limited in wall time
    (lanes stretch each episode's wall time); with auto, AUTO_LANES for a policy that answers all lanes in one call
    on one of our simulators, else one."""
    requested = parse_lanes(value)
    why = (
        "an operator stages it" if operator
        else "it is not simulated" if not getattr(robot, "simulated", False)
        else "it runs at a fixed --fps" if fps is not None
        else "--max_episode_s limits episodes in wall time" if max_episode_s is not None
        else None
    )  # fmt: skip
    if why is not None:
        if requested not in (None, 1):
            raise LanesError(f"--lanes={requested}: {robot.name} runs one trial at a time ({why}); drop --lanes")
        return 1
    if requested is not None:
        return requested
    return AUTO_LANES if _ours(robot) and batches_lanes(policy) else 1  # copies per lane would only add steps


def _ours(robot: Any) -> bool:
    """Whether `robot` is one of our simulators, not a subclass from another package: a plugin's copies may share a
    link or state (a counter on the class), so it gets lanes only when asked for."""
    return type(robot).__module__.split(".")[0] == "lerobot_contrast"


def lane_threads(lanes: int) -> int:
    """Threads that answer the lanes: two where this process may use two cores, half the lanes each."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    return 2 if lanes > 1 and cores > 1 else 1


def use_threads(threads: int = EVAL_THREADS) -> None:
    """Set torch's thread counts for the evaluation (inter-op only where torch has not started using it)."""
    import torch

    torch.set_num_threads(threads)
    with suppress(RuntimeError):  # fixed for good once parallel work ran in this process
        torch.set_num_interop_threads(threads)
