"""The operator's console in an interleaved session: before each policy's run it says which run of the trial this is
and, after the first, to put the scene back to the trial's start; with `--blind=true` it names the policy only once
the trial is labelled."""

from __future__ import annotations

from typing import Any

from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.operators.base import Label, Staging
from lerobot_contrast.operators.console import OperatorConsole


class PairConsole:
    """One policy's view of the shared `OperatorConsole`; `session` (an Interleaver) says where the trial stands."""

    def __init__(self, console: OperatorConsole, label: str, blind: bool) -> None:
        self.console, self.policy, self.blind = console, label, blind
        self.session: Any = None

    def __getattr__(self, name: str) -> Any:  # answers, and whatever else the runner asks the console
        return getattr(self.console, name)

    def _say(self, text: str) -> None:
        self.console.say(text)

    def stage(self, context: TrialContext) -> Staging:
        turn = f"policy {self.session.position + 1} of {len(self.session.order)}"
        who = f"{turn} (blind: named once labelled)" if self.blind else f"{turn}: {self.policy}"
        if self.session.restage:
            self._say(
                f"[bold]restage[/] trial {context.index + 1} for the next policy, {who}: put back what the last "
                "policy moved (listed below)"
            )
        else:
            self._say(f"trial {context.index + 1}, {who}")
        return self.console.stage(context)

    def label(self, *args: Any) -> Label:
        label = self.console.label(*args)
        if self.blind and label.action == "done":
            self._say(f"labelled; that run was {self.policy}")
        return label
