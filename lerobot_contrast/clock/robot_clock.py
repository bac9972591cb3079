"""The robot's clock: every wait for the robot (an episode's pacing at --fps, the arm's motions and settles, the
time limits and the robot-time cost) is taken from it. The wall clock by default; with `--clock=ADDRESS` the virtual
SO-101's simulated clock (`python -m lerobot_contrast.twin --clock=sim`), which moves only when asked
(clock/simulated.py). One clock per process, chosen by the command's entry point with `use_clock`."""

from __future__ import annotations

import time
from typing import Any, Protocol

from lerobot_contrast.contrast.errors import UserError

WALL = "wall"


class Clock(Protocol):
    simulated: bool

    def now(self) -> float: ...  # seconds, from an arbitrary origin

    # Let the robot run on for `seconds` (nothing where <= 0). `watched=False`: nothing reads the camera before the
    # next sleep (the arm moving itself), so a simulated camera need not draw a frame.
    def sleep(self, seconds: float, watched: bool = True) -> None: ...

    def look(self) -> None: ...  # the camera's next frame is of a moment after this call

    def watch(self, robot: Any) -> None: ...  # a robot connected: its cameras are read on this clock


class WallClock:
    """Real time: the robot runs on by itself, and the camera streams."""

    simulated = False

    def now(self) -> float:
        return time.perf_counter()

    def sleep(self, seconds: float, watched: bool = True) -> None:
        if seconds > 0:
            from lerobot.utils.robot_utils import precise_sleep  # LeRobot loads once a robot runs, not with the flags

            precise_sleep(seconds)

    def look(self) -> None:
        return None

    def watch(self, robot: Any) -> None:
        return None


_clock: Clock = WallClock()


def robot_clock() -> Clock:
    return _clock


def check_clock(address: str | None) -> None:
    """One line for a --clock that names no clock (checked before anything connects)."""
    if address not in (None, "", WALL) and not address.startswith("tcp://"):
        raise UserError(f"--clock={address}: give wall, or the tcp://HOST:PORT a twin started with --clock=sim printed")


def use_clock(address: str | None) -> Clock:
    """Take every wait from the clock `address` names (wall, or the twin's tcp://HOST:PORT) from now on."""
    global _clock
    check_clock(address)
    if address in (None, "", WALL):
        _clock = WallClock()
    else:
        from lerobot_contrast.clock.simulated import SimClock

        _clock = SimClock(address)
    return _clock
