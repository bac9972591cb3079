"""The interleaved trial loop: each planned trial is staged once on the shared contrast chain, then run by every
policy in turn, the scene restaged to the trial's start between them (counted as cost). The order rotates by base,
so no policy always gets the freshly staged scene, and the chain goes on from the scene the last policy left.

Each policy's trials come from the single-policy loop (`evaluation.trials`) over its own `LoopState`, journalled in
its own run directory; this module only moves the shared scene between them."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field

from lerobot_contrast.contrast.cost import CostModel
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.contrast.strategy import PlannedTrial, exceeds_budget
from lerobot_contrast.contrast.trial import Outcome, TrialContext, TrialRecord
from lerobot_contrast.record.observer import EpisodeObserver
from lerobot_contrast.spine.evaluation import STAGED, Evaluation, Execute, LoopState, trials


@dataclass
class Seat:
    """One policy's place in the session: its evaluation (policy, observers, run directory), its journal's records,
    and how a trial runs with it."""

    label: str
    evaluation: Evaluation
    records: list[TrialRecord]
    execute: Execute
    append: Callable[[TrialRecord], None]
    observers: Sequence[EpisodeObserver] = ()
    state: LoopState = field(init=False)
    upcoming: Iterator[TrialRecord] | None = field(default=None, init=False)


def policy_order(labels: Sequence[str], rank: int) -> list[str]:
    """The order of the policies on the `rank`-th base: rotated by one each base (A,B then B,A for two)."""
    k = rank % len(labels)
    return [*labels[k:], *labels[:k]]


def base_ranks(plan: Sequence[PlannedTrial]) -> dict[str, int]:
    ranks: dict[str, int] = {}
    for trial in plan:
        ranks.setdefault(trial.base.id, len(ranks))
    return ranks


class Interleaver:
    """Steps the seats through the plan trial by trial; `run` yields each trial's records once all policies ran it."""

    def __init__(
        self, seats: Sequence[Seat], plan: Sequence[PlannedTrial], cost_model: CostModel, budget: float | None,
        initial: Scene,
    ) -> None:  # fmt: skip
        self.seats, self.plan, self.cost_model, self.budget = list(seats), plan, cost_model, budget
        self.by_label = {seat.label: seat for seat in self.seats}
        self.ranks = base_ranks(plan)
        self.initial = initial
        self.before = initial  # the scene the next policy of the current trial is restaged from
        self.order: list[str] = []  # the current trial's order, the running policy's position in it, and whether
        self.position, self.restage = 0, False  # an earlier policy left the scene to be restaged
        for seat in self.seats:
            seat.state = LoopState.resume(seat.records, initial)
            ev = dataclasses.replace(seat.evaluation, execute=None)
            seat.upcoming = trials(ev, seat.state, self._execute(seat), seat.observers)

    def order_of(self, index: int) -> list[str]:
        return policy_order([s.label for s in self.seats], self.ranks[self.plan[index].base.id])

    @property
    def total_cost(self) -> float:
        return sum(seat.state.cumulative_cost for seat in self.seats)

    def run(self, stop: Callable[[], bool] = lambda: False) -> Iterator[dict[str, TrialRecord]]:
        """Run the plan from the first trial some policy has not recorded; trials all policies recorded before are
        yielded too (without running), so a caller rebuilds its state from them."""
        chain = self.initial
        for index in range(len(self.plan)):
            if all(len(seat.records) > index for seat in self.seats):
                chain = self._after(index, chain, {s.label: s.records[index] for s in self.seats})
                yield {s.label: s.records[index] for s in self.seats}
                continue
            if stop() or exceeds_budget(self.total_cost, self.budget):
                return
            records = self._trial(index, chain)
            if records is None:
                return
            chain = self.before
            yield records

    def _after(self, index: int, chain: Scene, records: dict[str, TrialRecord]) -> Scene:
        """The chain's scene after trial `index`: the scene the last policy that staged it left."""
        for label in self.order_of(index):
            if records[label].status in STAGED and records[label].scene_after is not None:
                chain = records[label].scene_after
        return chain

    def _trial(self, index: int, chain: Scene) -> dict[str, TrialRecord] | None:
        self.order, self.before, self.restage = self.order_of(index), chain, False
        for seat in self.seats:
            if len(seat.records) == index:  # its next trial starts from the chain's scene, like every policy's
                seat.state.scene = chain
        records = {}
        for position, label in enumerate(self.order):
            seat = self.by_label[label]
            self.position = position
            if len(seat.records) > index:  # recorded before the run was cut between the policies of this trial
                record = seat.records[index]
            else:
                record = next(seat.upcoming, None)
                if record is None:
                    return None
                seat.append(record)
            if record.status in STAGED and record.scene_after is not None:
                self.before, self.restage = record.scene_after, True
            records[label] = record
        return {s.label: records[s.label] for s in self.seats}

    def _execute(self, seat: Seat) -> Execute:
        def execute(context: TrialContext) -> Outcome:
            """The trial staged from the scene the previous policy left (the chain's, for the first)."""
            staged = dataclasses.replace(
                context, current=self.before, planned_cost=self.cost_model(self.before, context.instance.scene)
            )
            outcome = seat.execute(staged)
            pairing = {"policy": seat.label, "order": self.order, "position": self.position, "restage": self.restage}
            return dataclasses.replace(
                outcome,
                cost=staged.planned_cost if outcome.cost is None else outcome.cost,
                extra={**outcome.extra, "pairing": pairing},
            )

        return execute
