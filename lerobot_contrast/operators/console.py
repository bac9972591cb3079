"""The person at the console: what to stage before each trial, keys during it, and the outcome label after it.

Answers are lines read from a stream (the terminal, or a scripted file in tests and CI) on a background
thread, so the control loop can poll for the in-trial keys without ever blocking on input. With a structured
channel (channel.py), each prompt is also written as one JSON line for a program that answers it.
"""

from __future__ import annotations

import collections
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from typing import IO, Any

from rich.console import Console
from rich.table import Table

from lerobot_contrast.contrast.perturbation import perturbation_label
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.contrast.staging import staging_moves
from lerobot_contrast.contrast.task import Judgement
from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.operators.base import Label, SessionStopped, Staging

# In-trial keys (a letter, then Enter): end the episode as a success or a failure, or stop the robot now.
TRIAL_KEYS = {"s": "success", "f": "failure", "e": "estop"}
AXIS_MEANING = {
    "L": "new wording, same behaviour",
    "LB": "new wording, new behaviour",
    "S": "scene change, same behaviour",
    "SB": "scene change, new behaviour",
}


class Answers:
    """Lines from `stream`, read on a daemon thread into a queue that the control loop polls."""

    def __init__(self, stream: IO[str]) -> None:
        self._lines: collections.deque[str] = collections.deque()
        self._closed = False
        self.served = 0  # the answers next() has handed out: what an offer names as the prompt it answers
        self._ready = threading.Condition()
        self.taken: list[Callable[[], None]] = []  # told each time an answer is taken (the person's page)
        threading.Thread(target=self._read, args=(stream,), daemon=True, name="operator-input").start()

    def offer(self, line: str, key: bool = False, served: int | None = None) -> bool:
        """Queue an answer from elsewhere than the stream (the person's page), unless one is already waiting or, with
        `served` (the count when the prompt was shown), the prompt had its answer: the first answer to a prompt counts,
        and a second would answer the prompt after it. An in-trial `key` goes first in the queue, where take_key
        looks, whatever else waits there (an emergency stop above all)."""
        with self._ready:
            if key:
                self._lines.appendleft(line)
            elif self._lines or (served is not None and served != self.served):
                return False
            else:
                self._lines.append(line)
            self._ready.notify_all()
            return True

    def _read(self, stream: IO[str]) -> None:
        for line in iter(stream.readline, ""):
            with self._ready:
                self._lines.append(line.strip())
                self._ready.notify_all()
        with self._ready:
            self._closed = True
            self._ready.notify_all()

    def take_key(self) -> str | None:
        """The next line if it is an in-trial key; other answers stay queued for the prompts after the trial."""
        with self._ready:
            if self._lines and self._lines[0].lower() in TRIAL_KEYS:
                key = TRIAL_KEYS[self._lines.popleft().lower()]
            else:
                return None
        self._tell()
        return key

    def next(self) -> str:
        """Block for the next answer; the end of the input stops the session."""
        with self._ready:
            while not self._lines:
                if self._closed:
                    raise SessionStopped("the operator's input ended")
                self._ready.wait()
            line = self._lines.popleft()
            self.served += 1
        self._tell()
        return line

    def _tell(self) -> None:
        for told in self.taken:
            told()


class OperatorConsole:
    """The operator interface (base.Operator) answered by a person. `bench`: a calibrated camera that shows each
    target and checks the staging (staging.check.Bench); `channels`: where each prompt is also sent (a JSON file for a
    program, the person's page, notifications); one that shows what the console says has `said_line`."""

    def __init__(
        self,
        answers: Answers,
        console: Console | None = None,
        unit: str = "m",
        bench: Any = None,
        channels: Sequence[Any] = (),
    ) -> None:
        self.answers = answers
        self.console = console or Console(highlight=False)
        self.unit = unit
        self.bench = bench
        self.channels = list(channels)
        self._trial: dict[str, Any] = {}  # the trial being staged, as the channel names it

    def _send(self, **message: Any) -> None:
        for channel in self.channels:
            channel.send(**message)

    def say(self, text: str) -> None:
        self.console.print(text)
        for channel in self.channels:
            if hasattr(channel, "said_line"):
                channel.said_line(text)

    def finish(self, text: str) -> None:
        """The session ended or stopped (`text` says how): told on every channel, then the channels close."""
        self._send(event="session", text=text)
        for channel in self.channels:
            if hasattr(channel, "close"):
                channel.close()

    def note(self, event: str, **facts: Any) -> None:
        """Tell a program on the channel something that needs no answer (the arm's own label, for one)."""
        self._send(event=event, **facts, **self._trial)

    def take_key(self) -> str | None:
        return self.answers.take_key()

    def announce(self, context: TrialContext) -> dict[str, list[float] | None]:
        """Show the trial and what to move for it; returns each object to move and its target (None: off the
        workspace)."""
        self._trial = {"trial": context.index, "instruction": context.instance.instruction}
        moves = self._show_trial(context)
        self._send(event="trial", of=context.planned_trials, moves=moves, instance=context.instance.to_json(),
                   **self._trial)  # fmt: skip
        return moves

    def scene_after(self, robot: Any, staged: Scene, staging: Staging) -> Scene:
        if staging.measured is None or self.bench is None:
            return staged
        return self.bench.scene_after(robot, staged, staging.measured)  # where the camera saw them

    def stage(self, context: TrialContext) -> Staging:
        """Show what to move for this trial and time the operator from the prompt to "ready"."""
        moves = self.announce(context)
        start = time.monotonic()
        while True:
            self.console.print(
                "[bold]Enter[/] when staged · [bold]c METRES[/] if you moved things differently · "
                "[bold]k[/] skip trial · [bold]q[/] stop session"
            )
            self._send(prompt="stage", of=context.planned_trials, moves=moves, **self._trial)
            answer = self.answers.next()
            if answer in ("", "ready", "y"):
                return Staging("ready", time.monotonic() - start)
            if answer in ("k", "q"):
                return Staging("skip" if answer == "k" else "stop", time.monotonic() - start)
            moved = _number(answer, "c")
            if moved is not None and moved >= 0:
                return Staging("ready", time.monotonic() - start, moved)
            self.console.print(f"[red]not understood: {answer!r}[/]")

    def _show_trial(self, context: TrialContext) -> dict[str, list[float] | None]:
        """Print what to move; returns each object to move and its target (None: off the workspace)."""
        instance = context.instance
        axis = f" ({AXIS_MEANING[context.axis]})" if context.axis else ""
        self.console.rule(
            f"trial {context.index + 1}/{context.planned_trials} · {instance.base_id} · "
            f"{perturbation_label(instance.perturbation)}{axis}"
        )
        self.console.print(f"instruction: [bold]{instance.instruction}[/]")
        moves = staging_moves(context.current, instance.scene)
        if moves:
            table = Table("move", "from", "to", "distance (m)")
            for move in moves:
                moved = f"{move.distance:.3f}" if move.start and move.end else "in or out"
                table.add_row(move.name, _where(move.start), _where(move.end), moved)
            self.console.print(table)
        moved = {move.name for move in moves}
        still = sorted(set(instance.scene.objects) - moved)
        if still:
            self.console.print(f"leave as they are: {', '.join(still)}")
        if not moves:
            self.console.print("nothing to move")
        self.console.print(f"planned cost: {context.planned_cost:.2f} {self.unit}")
        return {move.name: None if move.end is None else [move.end.x, move.end.y] for move in moves}

    def fix_or_accept(self, off: Mapping[str, float | None], tolerance: float) -> str:
        """Say which checked objects the camera found off target; "fix" (measure again), "accept" or "stop"."""
        table = Table("object", "measured", title=f"staging check (tolerance {tolerance * 100:g} cm)")
        for name, distance in off.items():
            said = "not seen" if distance is None else f"{distance * 100:.1f} cm off" if distance > 0 else "ok"
            table.add_row(name, f"[red]{said}[/]" if said != "ok" else said)
        self.console.print(table)
        while True:
            self.console.print(
                "[bold]Enter[/] after fixing them to measure again · [bold]a[/] accept as placed · [bold]q[/] stop session"
            )
            self._send(prompt="check", off=dict(off), tolerance=tolerance)
            answer = self.answers.next().lower()
            if answer in ("", "a", "q"):
                return {"": "fix", "a": "accept", "q": "stop"}[answer]
            self.console.print(f"[red]not understood: {answer!r}[/]")

    def call(self, trouble: str, fix: Mapping[str, list[float] | None]) -> str:
        """Ring for a person at the bench (what to fix, and where each object goes: `fix`, None for off the
        workspace) and wait: "done" on Enter, "stop" on q."""
        self.console.print(f"\a[bold red]a person is needed at the bench:[/] {trouble}")
        for name, where in fix.items():
            self.console.print(f"  put {name} {'off the workspace' if where is None else _where_xy(where)}")
        while True:
            self.console.print("[bold]Enter[/] once fixed · [bold]q[/] stop session")
            self._send(prompt="call", trouble=trouble, fix=dict(fix), **self._trial)
            answer = self.answers.next().lower()
            if answer in ("", "q"):
                return "stop" if answer == "q" else "done"
            self.console.print(f"[red]not understood: {answer!r}[/]")

    def running(self) -> None:
        self.console.print("running · [bold]s[/] success · [bold]f[/] failure · [bold]e[/] EMERGENCY STOP (then Enter)")
        self._send(event="running")

    def aborted(self, reason: str) -> Label:
        self.console.print(f"[bold red]trial aborted: {reason}[/]")
        self.console.print("[bold]Enter[/] to continue with the next trial · [bold]q[/] stop session")
        self._send(prompt="aborted", reason=reason)
        while True:
            answer = self.answers.next()
            if answer in ("", "q"):
                return Label("stop" if answer == "q" else "done")

    def label(self, subgoals: Sequence[str], suggestion: Judgement | None, early: str | None) -> Label:
        """Ask how the trial went: success/failure, or how many subgoals were reached, in order."""
        if early is not None and not subgoals:
            return Label("done", success=early == "success", progress=float(early == "success"))
        default = _suggested(suggestion, subgoals)
        choices = f"0-{len(subgoals)} subgoals reached ({', '.join(subgoals)})" if subgoals else "y success · n failure"
        while True:
            self.console.print(
                f"outcome? {choices} · [bold]p FRACTION[/] progress · [bold]r[/] redo · [bold]k[/] skip · "
                f"[bold]q[/] stop (this trial is not recorded){default[1]}"
            )
            self._send(prompt="label", subgoals=list(subgoals), **self._trial)
            answer = self.answers.next().lower()
            if answer == "" and default[0] is not None:
                return default[0]
            if answer in ("r", "k", "q"):
                return Label({"r": "redo", "k": "skip", "q": "stop"}[answer])
            parsed = _parse_label(answer, len(subgoals))
            if parsed is not None:
                return parsed
            self.console.print(f"[red]not understood: {answer!r}[/]")


def _parse_label(answer: str, n_subgoals: int) -> Label | None:
    if not n_subgoals and answer in ("y", "n"):
        return Label("done", success=answer == "y", progress=float(answer == "y"))
    if n_subgoals and answer.isdigit() and int(answer) <= n_subgoals:
        reached = int(answer)
        return Label("done", success=reached == n_subgoals, progress=reached / n_subgoals)
    progress = _number(answer, "p")
    if progress is not None and 0.0 <= progress <= 1.0:
        return Label("done", success=progress >= 1.0, progress=progress)
    return None


def _suggested(suggestion: Judgement | None, subgoals: Sequence[str]) -> tuple[Label | None, str]:
    if suggestion is None:
        return None, ""
    progress = suggestion.progress if suggestion.progress is not None else float(suggestion.success)
    label = Label("done", success=suggestion.success, progress=progress)
    said = (
        f"{round(progress * len(subgoals))} subgoals" if subgoals else ("success" if suggestion.success else "failure")
    )
    return label, f" · [bold]Enter[/] accepts what the scene shows: {said}"


def _number(answer: str, prefix: str) -> float | None:
    head, _, value = answer.partition(" ")
    if head != prefix:
        return None
    try:
        return float(value)
    except ValueError:
        return None


def _where_xy(xy: list[float]) -> str:
    return f"at ({xy[0]:+.3f}, {xy[1]:+.3f})"


def _where(pose) -> str:
    return "(off the workspace)" if pose is None else f"({pose.x:+.3f}, {pose.y:+.3f})"
