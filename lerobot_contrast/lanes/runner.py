"""Run the plan's chains side by side. A chain is a trial staged in full and the trials staged from the scene it
leaves (a base and its perturbations, its repeats); chains share nothing in simulation, so each lane, a copy of the
simulated robot, runs one at a time, and every control step the policy answers all lanes mid-episode at once.

The evaluation still asks for each trial in plan order (`LaneRunner(context)`), with the context the run's history
gives it; the lane's episode is then replayed to the observers, so journal, recordings and datasets are written as
with one lane. What a lane ran past the point where the run stops is never asked for, so never recorded."""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Generator, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Protocol

from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.contrast.staging import Staged, materialize, trial_rng
from lerobot_contrast.contrast.strategy import PlannedTrial
from lerobot_contrast.contrast.task import Task
from lerobot_contrast.contrast.trial import Outcome, TrialContext
from lerobot_contrast.lanes.seats import PolicyFor, Seat, lane_policy
from lerobot_contrast.policies.base import Policy
from lerobot_contrast.record.observer import EpisodeObserver, QuietObserver

# Trials whose staging was paid for: the scene they left behind is where the next one starts.
STAGED = ("done", "aborted")
# Bytes of observations the lanes' episodes may hold for their turn to be recorded (those waiting and those running);
# past it only the trial earliest in plan order steps, so memory stays bounded whatever a step's observation weighs
# (a 200-step episode of the apartment's camera and depth images holds 430 MB).
HELD_BYTES = 1 << 30

# (trial, staged, scene the lane left) -> the trial's context as the lane runs it.
ContextFor = Callable[[PlannedTrial, Staged, Scene], TrialContext]


class TrialRunner(Protocol):
    """What a lane asks of the evaluator's runner (run/runner.py's RobotRunner): one trial at a time as a generator
    of steps, the observers watching it, and why it stopped the robot, if it did."""

    observers: list[EpisodeObserver]

    @property
    def halted(self) -> Exception | None: ...

    def trial(self, context: TrialContext) -> Generator[dict[str, Any], dict[str, Any], Outcome]: ...


# (robot, policy seat, observers) -> the runner of one lane's trials.
RunnerFor = Callable[[Any, Seat, Sequence[EpisodeObserver]], TrialRunner]


def chains(plan: Sequence[PlannedTrial]) -> list[list[PlannedTrial]]:
    """`plan` cut where a trial is staged in full whatever scene it starts from."""
    cut: list[list[PlannedTrial]] = []
    for trial in plan:
        if not cut or (trial.staging == "reset" and trial.repeat == 0):
            cut.append([])
        cut[-1].append(trial)
    return cut


class EpisodeTape(QuietObserver):
    """Holds a lane's episode as the observers would have seen it, to be played to them in plan order."""

    def __init__(self) -> None:
        self.features: dict[str, dict] = {}
        self.pose_keys: tuple[str, str] | None = None
        self.steps: list[tuple[float, dict[str, Any], dict[str, Any]]] = []
        self.nbytes = 0
        self.started = False  # a trial refused before its episode (a robot lost earlier) shows the observers nothing

    def start(self, context: TrialContext, features: dict[str, dict], pose_keys: tuple[str, str] | None) -> None:
        self.features, self.pose_keys, self.steps, self.nbytes, self.started = features, pose_keys, [], 0, True

    def step(self, timestamp_s: float, observation: dict[str, Any], action: dict[str, Any]) -> None:
        kept = {k: v.copy() if hasattr(v, "copy") else v for k, v in observation.items()}  # robots reuse buffers
        self.steps.append((timestamp_s, kept, dict(action)))
        self.nbytes += sum(getattr(v, "nbytes", 8) for v in kept.values())

    def play(self, context: TrialContext, observers: Sequence[EpisodeObserver]) -> None:
        if not self.started:
            return
        for observer in observers:
            observer.start(context, self.features, self.pose_keys)
        for timestamp_s, observation, action in self.steps:
            for observer in observers:
                observer.step(timestamp_s, observation, action)


@dataclass
class Result:
    """A trial a lane finished: what it ran, how it ended (or what it raised), and its episode for the observers."""

    staged: Staged
    outcome: Outcome | None
    error: BaseException | None
    tape: EpisodeTape | None


@dataclass
class Lane:
    index: int
    runner: TrialRunner
    tape: EpisodeTape | None
    chain: deque[PlannedTrial] = field(default_factory=deque)
    scene: Scene | None = None
    previous: Staged | None = None
    trial: PlannedTrial | None = None
    staged: Staged | None = None
    steps: Generator[dict[str, Any], dict[str, Any], Outcome] | None = None
    observation: dict[str, Any] | None = None


class LaneRunner:
    """An `Execute` for `evaluation.trials`: the outcome of each trial asked for, in plan order, from the lanes."""

    def __init__(
        self,
        task: Task,
        plan: Sequence[PlannedTrial],
        seed: int,
        start: tuple[Scene, Staged | None],
        robot: Any,
        lanes: int,
        policy: Policy,
        runner_for: RunnerFor,
        context_for: ContextFor,
        observers: Sequence[EpisodeObserver] = (),
        policy_for: PolicyFor | None = None,
        threads: int = 1,
    ) -> None:
        self.task, self.seed, self.context_for = task, seed, context_for
        self.copies = [_copy(robot) for _ in range(lanes - 1)]
        self.policy = lane_policy(policy, [robot, *self.copies], policy_for, threads)
        self.observers = list(observers)
        # With two threads, half the lanes are answered beside the other half's answer and steps (torch and the
        # renderer let go of the GIL); a row's action is the same in any batch, so the split changes no result.
        self.pool = ThreadPoolExecutor(1, "lanes") if threads > 1 and self.policy.batched else None
        self.waiting = deque(chains(plan))
        self.results: dict[int, Result] = {}
        self.lanes: list[Lane] = []
        for i, lane_robot in enumerate([robot, *self.copies]):
            tape = EpisodeTape() if self.observers else None
            runner = runner_for(lane_robot, Seat(self.policy, i, policy.name), [tape] if tape else [])
            self.lanes.append(Lane(i, runner, tape))
        self.start_scene, self.start_previous = start
        self.head = plan[0].index if plan else -1
        # The first trial after which a lane's robot was lost for good: with one robot, every later trial of the
        # run is refused, whichever chain it belongs to.
        self.halt: tuple[int, Exception] | None = None

    def __call__(self, context: TrialContext) -> Outcome:
        if self.halt is not None and context.index > self.halt[0]:
            raise self.halt[1]
        while context.index not in self.results:
            self._advance()
        result = self.results.pop(context.index)
        if result.staged.instance != context.instance:
            raise RuntimeError(f"lanes: trial {context.index} ran another instance than the run's history gives")
        if result.tape is not None:
            result.tape.play(context, self.observers)
        if result.error is not None:
            raise result.error
        return result.outcome

    def close(self) -> None:
        """Disconnect the robot's copies (the first lane's robot is the caller's)."""
        if self.pool is not None:
            self.pool.shutdown()
            self.pool = None
        for robot in self.copies:
            if robot.is_connected:
                robot.disconnect()
        self.copies = []

    def _advance(self) -> None:
        """Give idle lanes the next chains, then take one control step on every lane mid-episode (on the one whose
        trial comes first in plan order, which the run needs soonest, while the episodes held reach HELD_BYTES)."""
        taken = False
        for lane in self.lanes:
            if lane.observation is None and self.waiting and self._may_run_ahead():
                self._take_chain(lane, self.waiting.popleft())
                taken = True
        active = [lane for lane in self.lanes if lane.observation is not None]
        if active and self._held() >= HELD_BYTES:
            active = [min(active, key=lambda lane: lane.trial.index)]
        if not active:  # the chains taken may have ended without a step (episodes shared by a sweep's cells)
            if not self.waiting and not taken:
                raise RuntimeError("lanes: a trial was asked for that no chain of the plan holds")
            return
        if self.pool is None or len(active) < 2:
            self._step(active)
            return
        first, second = active[: (len(active) + 1) // 2], active[(len(active) + 1) // 2 :]
        later = self.pool.submit(self._answer, second, 1)
        self._step(first)
        for lane, action in zip(second, later.result(), strict=True):
            self._send(lane, action)

    def _answer(self, lanes: Sequence[Lane], thread: int = 0) -> list[dict[str, Any]]:
        return self.policy.act([lane.index for lane in lanes], [lane.observation for lane in lanes], thread)

    def _step(self, lanes: Sequence[Lane]) -> None:
        for lane, action in zip(lanes, self._answer(lanes), strict=True):
            self._send(lane, action)

    def lanes_busy(self) -> bool:
        return any(lane.observation is not None for lane in self.lanes)

    def _held(self) -> int:
        """Bytes of observations the tapes hold: the episodes waiting for their turn and those running."""
        tapes = [result.tape for result in self.results.values()] + [lane.tape for lane in self.lanes]
        return sum(tape.nbytes for tape in tapes if tape is not None)

    def _may_run_ahead(self) -> bool:
        """Whether the episodes held leave room for another chain (one always runs)."""
        return self._held() < HELD_BYTES or not self.lanes_busy()

    def _take_chain(self, lane: Lane, chain: list[PlannedTrial]) -> None:
        """The first chain goes on from where the run stands (a resumed run may stop mid-chain); others start anew."""
        lane.chain = deque(chain)
        head = chain[0].index == self.head
        lane.scene, lane.previous = (self.start_scene, self.start_previous) if head else (None, None)
        self._next_trial(lane)

    def _next_trial(self, lane: Lane) -> None:
        """Start the lane's next applicable trial, until one needs the policy or the chain is done."""
        while lane.chain and lane.observation is None:
            trial = lane.chain.popleft()
            scene = lane.scene if lane.scene is not None else trial.base.scene
            staged = materialize(trial, self.task, scene, lane.previous, trial_rng(self.seed, trial.index))
            lane.previous = staged
            if staged.instance is None:
                continue
            lane.trial, lane.staged = trial, staged
            lane.steps = lane.runner.trial(self.context_for(trial, staged, scene))
            self._resume(lane, lambda steps: next(steps))

    def _send(self, lane: Lane, action: dict[str, Any]) -> None:
        self._resume(lane, lambda steps: steps.send(action))
        if lane.observation is None:
            self._next_trial(lane)

    def _resume(self, lane: Lane, step: Callable[[Generator], dict[str, Any]]) -> None:
        try:
            lane.observation = step(lane.steps)
            return
        except StopIteration as end:
            outcome, error = end.value, None
        except Exception as raised:  # raised when the run reaches this trial, as with one lane
            outcome, error = None, raised
            lane.chain.clear()
        lane.observation = None
        self.results[lane.trial.index] = Result(lane.staged, outcome, error, lane.tape)
        if lane.tape is not None:
            lane.tape = EpisodeTape()
            lane.runner.observers = [lane.tape]
        if outcome is not None and outcome.status in STAGED:
            lane.scene = outcome.scene_after
        halted = lane.runner.halted
        if halted is not None and (self.halt is None or lane.trial.index < self.halt[0]):
            self.halt = (lane.trial.index, halted)


def _copy(robot: Any) -> Any:
    """Another connected simulator of the same config: a simulated world is rebuilt on connect."""
    copy = type(robot)(robot.config)
    copy.connect()
    return copy
