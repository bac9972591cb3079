"""What a person watching a run sees: a header before the first trial, then a progress bar that redraws on a
terminal (plain lines every twentieth of the plan into a file or CI), counting not-applicable trials."""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Sequence
from pathlib import Path

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

from lerobot_contrast.contrast.trial import TrialRecord
from lerobot_contrast.terminal.lines import trial_line

PLAIN_STEPS = 20  # plain progress lines per run, into a file or CI


def header_lines(settings: dict[str, object], run_dir: Path, resume: str) -> list[str]:
    """Task, policy, strategy, plan size, run directory and how to resume, before the first trial."""
    plan = f"{settings['planned_trials']} planned trials"
    budget = "" if settings.get("budget") is None else f", budget {settings['budget']:g} {settings['cost_unit']}"
    return [
        f"task {settings['task']} · policy {settings['policy']} · strategy {settings['strategy']} · "
        f"robot {settings['robot']} · seed {settings['seed']}",
        f"plan: {plan}{budget}",
        f"run directory: {run_dir}",
        f"stop any time with Ctrl-C; continue with: {resume}",
    ]


class RunProgress:
    """Told of every trial as the journal records it (`Evaluation.progress`); shows done/planned, trials run and
    not applicable, cost spent and time left. With `verbose`, also today's line per trial (an aborted one always)."""

    def __init__(
        self,
        planned: int,
        unit: str,
        console: Console | None = None,
        verbose: bool = False,
        already: Sequence[TrialRecord] = (),
        live: bool | None = None,
    ) -> None:
        self.console = console or Console(highlight=False)
        self.planned, self.unit, self.verbose = planned, unit, verbose
        self.counts = Counter(r.status for r in already)
        self.completed, self.first = len(already), len(already)
        self.spent = max((r.cumulative_cost for r in already), default=0.0)
        self.live = self.console.is_terminal if live is None else live
        self.step = max(1, planned // PLAIN_STEPS)
        self.started = time.monotonic()
        self.bar: Progress | None = None

    def __enter__(self) -> RunProgress:
        if self.live:
            self.bar = Progress(
                TextColumn("trial"),
                MofNCompleteColumn(),
                BarColumn(),
                TextColumn("{task.description}"),
                TimeRemainingColumn(),
                TextColumn("left"),
                console=self.console,
                transient=True,
            )
            self.task = self.bar.add_task(self.counts_text(), total=self.planned, completed=self.completed)
            self.bar.start()
        return self

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.stop()
        if self.completed > self.first:
            self.console.print(
                f"{self.completed}/{self.planned} trials · {self.counts_text()}", soft_wrap=True, highlight=False
            )

    def __call__(self, record: TrialRecord) -> None:
        self.completed += 1
        self.counts[record.status] += 1
        if record.status in ("done", "aborted"):
            self.spent = record.cumulative_cost
        if self.verbose or record.status == "aborted":  # an aborted trial says why, whether or not lines are asked for
            self.console.print(trial_line(record, self.unit), soft_wrap=True, markup=False, highlight=False)
        if self.bar is not None:
            self.bar.update(self.task, completed=self.completed, description=self.counts_text())
        elif self.completed % self.step == 0 and self.completed < self.planned:
            self.console.print(self.plain_line(), soft_wrap=True, highlight=False)

    def counts_text(self) -> str:
        ran = self.counts["done"]
        text = f"{ran} ran, {self.counts['not_applicable']} not applicable"
        for status in ("aborted", "skipped"):
            if self.counts[status]:
                text += f", {self.counts[status]} {status}"
        return f"{text} · {self.spent:.2f} {self.unit} spent"

    def plain_line(self) -> str:
        """The progress line for a file or CI: no redraw, so the time left is spelled out."""
        seen = self.completed - self.first
        left = (time.monotonic() - self.started) / seen * (self.planned - self.completed) if seen else 0.0
        return f"trial {self.completed}/{self.planned} · {self.counts_text()} · {_clock(left)} left"


def _clock(seconds: float) -> str:
    minutes, secs = divmod(round(seconds), 60)
    return f"{minutes // 60}:{minutes % 60:02d}:{secs:02d}"
