"""Each lane's view of the policy. A LeRobot policy that keeps every episode's memory apart (`lane_step`) answers all
lanes in one call; any other policy (a scripted one, or a LeRobot policy with one action queue for its whole batch,
as the chunking policies have) gets a copy per lane, asked lane by lane."""

from __future__ import annotations

import copy
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Protocol

import numpy as np

from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.policies.action_noise import NoisyPolicy
from lerobot_contrast.policies.base import Policy

Observation = Mapping[str, Any]
# Builds the run's policy for another copy of its robot.
PolicyFor = Callable[[Any], Policy]


class LanePolicy(Protocol):
    """A policy for `n` lanes: each lane starts its own episodes; one call answers the lanes mid-episode."""

    batched: bool  # one call of the policy for all lanes (else one per lane)

    def start(self, lane: int, context: TrialContext) -> None: ...

    def act(
        self, lanes: Sequence[int], observations: Sequence[Observation], thread: int = 0
    ) -> list[dict[str, float]]: ...

    def done(self, lane: int) -> bool: ...


class CopiedLanes:
    """A policy per lane (its reset and randomness are per trial, so each acts as the one would): built for the
    lane's own robot by `policy_for` (a scripted policy may read its robot's state), else a deep copy."""

    batched = False

    def __init__(self, policy: Policy, robots: Sequence[Any], policy_for: PolicyFor | None = None) -> None:
        others = [policy_for(robot) if policy_for else copy.deepcopy(policy) for robot in robots[1:]]
        self.copies = [policy, *others]

    def start(self, lane: int, context: TrialContext) -> None:
        self.copies[lane].reset(context)

    def act(self, lanes: Sequence[int], observations: Sequence[Observation], thread: int = 0) -> list[dict[str, float]]:
        return [self.copies[lane].act(obs) for lane, obs in zip(lanes, observations, strict=True)]

    def done(self, lane: int) -> bool:
        return bool(getattr(self.copies[lane], "done", False))


class BatchedLanes:
    """A LeRobot policy with `lane_step`: one call per control step, each lane's episode memory kept apart. With
    --policy.noise_std, each lane draws its noise from its own trial's randomness, as `NoisyPolicy` does."""

    batched = True

    def __init__(self, policy: Policy, n: int, threads: int = 1) -> None:
        self.noise_std = policy.noise_std if isinstance(policy, NoisyPolicy) else 0.0
        inner = policy.policy if isinstance(policy, NoisyPolicy) else policy
        self.policies = [inner, *(inner.lane_twin() for _ in range(threads - 1))]  # one per answering thread
        self.instructions = [""] * n
        self.memories: list[dict[str, Any]] = [{} for _ in range(n)]
        self.rngs = [np.random.default_rng(0) for _ in range(n)]

    def start(self, lane: int, context: TrialContext) -> None:
        self.instructions[lane] = context.instance.instruction
        self.memories[lane] = {}
        self.rngs[lane] = context.rng

    def act(self, lanes: Sequence[int], observations: Sequence[Observation], thread: int = 0) -> list[dict[str, float]]:
        instructions = [self.instructions[lane] for lane in lanes]
        actions = self.policies[thread].act_lanes(observations, instructions, [self.memories[lane] for lane in lanes])
        if self.noise_std > 0:
            actions = [self._noisy(action, self.rngs[lane]) for lane, action in zip(lanes, actions, strict=True)]
        return actions

    def _noisy(self, action: dict[str, float], rng: np.random.Generator) -> dict[str, float]:
        noise = rng.normal(0.0, self.noise_std, len(action))
        return {key: float(value) + float(n) for (key, value), n in zip(action.items(), noise, strict=True)}

    def done(self, lane: int) -> bool:
        return False


def batches_lanes(policy: Policy) -> bool:
    """Whether `policy` (through --policy.noise_std's wrapper) answers all lanes in one call."""
    inner = policy.policy if isinstance(policy, NoisyPolicy) else policy
    return getattr(inner, "batches_lanes", False)


def lane_policy(
    policy: Policy, robots: Sequence[Any], policy_for: PolicyFor | None = None, threads: int = 1
) -> LanePolicy:
    """The policy for a lane per robot in `robots` (the first is `policy`'s own), answered from `threads` threads."""
    if batches_lanes(policy):
        return BatchedLanes(policy, len(robots), threads)
    return CopiedLanes(policy, robots, policy_for)


class Seat:
    """Lane `lane`'s place at the policy, as the trial runner sees it: its reset and its `done`; the lanes' driver
    asks for the actions."""

    def __init__(self, lanes: LanePolicy, lane: int, name: str) -> None:
        self.lanes, self.lane, self.name = lanes, lane, name

    def reset(self, context: TrialContext) -> None:
        self.lanes.start(self.lane, context)

    @property
    def done(self) -> bool:
        return self.lanes.done(self.lane)

    def act(self, observation: Observation) -> dict[str, float]:
        return self.lanes.act([self.lane], [observation])[0]
