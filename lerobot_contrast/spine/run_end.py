"""How a run that ends before its plan is said: Ctrl-C, the operator's stop and a lost robot each get one line that
tells how to continue, and an exit code (130, 0 and 2). The single-policy run and the interleaved session share it."""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

from lerobot_contrast.operators.base import SessionStopped
from lerobot_contrast.spine.runner import RobotLostError

ENDED_EARLY = (KeyboardInterrupt, SessionStopped, RobotLostError)


def finish(operator: Any, text: str) -> None:
    """Tell the person's channels (their page, notifications) that the session ended or stopped, as `text` says."""
    console = getattr(operator, "person", operator)  # the arm's console is the person it calls
    if hasattr(console, "finish"):
        console.finish(text)


def tell_stopped(operator: Any, error: BaseException, resume: str) -> None:
    """Tell the person's channels that the session stopped on `error` (an interruption, the operator's stop, a lost
    robot, or a failure), with the command that continues it (`resume`)."""
    why = " ".join(str(error).split()) or "interrupted"
    finish(operator, f"the session stopped ({why}); continue with {resume}")


def say_ended_early(
    error: KeyboardInterrupt | SessionStopped | RobotLostError,
    resume: str,
    kept: str,
    recorded: Callable[[], int] | None = None,
) -> int:
    """Say why the run ended early and how to go on (`resume`: the flags that continue it); the exit code.
    `kept` says where the finished trials are; `recorded`, when given, counts them for the operator's stop."""
    if isinstance(error, KeyboardInterrupt):
        print(f"\ninterrupted: every finished trial is {kept}; continue with {resume}", file=sys.stderr)
        return 130
    if isinstance(error, SessionStopped):
        count = "" if recorded is None else f"; {recorded()} trials recorded"
        print(f"stopped: {error}{count}; continue with {resume}")
        return 0
    print(f"error: {error} with {resume}", file=sys.stderr)  # the robot was lost
    return 2
