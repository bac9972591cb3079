"""The scripted operator of the twin: runs `python -m lerobot_contrast.eval ... --operator=console` as a child, reads
from the console's structured channel what to move where, places each object through the twin's placement socket
(with a chosen error), presses Enter, and labels each trial from the twin's true scene with the task's own goal
check. A person typing at this terminal takes over the console's answers from then on.

    python -m lerobot_contrast.twin.operator [--placement=tcp://127.0.0.1:5556] [--placement_error=normal:0.005]
        [--seed=0] [--on_flagged=accept|fix] EVAL_FLAGS...
"""

from __future__ import annotations

import sys
import time
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.spine.flags import ScriptParser
from lerobot_contrast.twin.console_session import run_answered
from lerobot_contrast.twin.fates import ENDED, held_line
from lerobot_contrast.twin.placement_client import DEFAULT_ADDRESS, PlacementClient

# After placing, wait as a person's hands leave the table: the camera's latest frame is up to a few frames old, and
# the staging check reads it at Enter (measured on the twin: the frame read at once still showed the old pose).
SETTLE_S = 0.5
STRAY_M = 0.01  # an object this far from where the trial starts it was moved: put it back
LIFTED_M = 0.02  # an object this far above where it rested when staged is held, not put down


def held(heights: Mapping[str, float], resting: Mapping[str, float], gripped: Collection[str]) -> dict[str, float]:
    """The objects held in the gripper, each with how far (m) above where it rested when staged: lifted off its rest
    and touching the jaws (one lying on another object is lifted, not held)."""
    return {name: z - resting[name] for name, z in heights.items()
            if name in resting and name in gripped and z - resting[name] > LIFTED_M}  # fmt: skip


class OperatorError(Exception):
    """Something the scripted operator cannot do; its message is one line."""


@dataclass(frozen=True)
class PlacementError:
    """How far from its target an object lands: none, normal:SIGMA (metres per axis) or offset:D (exactly D metres
    in a random direction)."""

    kind: str = "none"
    size: float = 0.0

    @classmethod
    def parse(cls, text: str) -> PlacementError:
        kind, _, size = text.partition(":")
        try:
            error = cls(kind, float(size) if size else 0.0)
        except ValueError:
            error = cls("?", -1.0)
        if error.kind not in ("none", "normal", "offset") or error.size < 0 or (error.kind != "none") != bool(size):
            raise OperatorError(f"--placement_error={text}: give none, normal:SIGMA or offset:D (metres)")
        return error

    def draw(self, rng: np.random.Generator) -> tuple[float, float]:
        if self.kind == "normal":
            return tuple(rng.normal(0.0, self.size, 2))
        if self.kind == "offset":
            angle = rng.uniform(0, 2 * np.pi)
            return self.size * np.cos(angle), self.size * np.sin(angle)
        return 0.0, 0.0


class Plan:
    """What the run's flags say beyond each trial: its task (to judge with the task's own goal check) and where the
    twin keeps objects off the workspace. Each trial's instance comes from the channel, as the evaluator ran it."""

    def __init__(self, eval_argv: Sequence[str]):
        from lerobot_contrast.so101.scene import start_poses
        from lerobot_contrast.spine.build import check_robot_type, register_robots
        from lerobot_contrast.spine.config import EvalConfig, resume_args
        from lerobot_contrast.spine.flags import bool_flags, join_values, parse_config
        from lerobot_contrast.spine.run_setup import planned_evaluation

        argv = join_values(list(eval_argv), bool_flags(EvalConfig))
        check_robot_type(argv, register_robots())
        self.task = planned_evaluation(parse_config(EvalConfig, resume_args(argv))).task
        self.parking = start_poses(self.task.spec, None)  # where the twin keeps objects off the workspace

    def judge(self, instance: Instance, scene: Scene, lifted: Collection[str] = ()) -> bool:
        """Whether `instance` reached its goal in `scene`; an object still `lifted` (in the gripper) is not placed,
        wherever it hangs."""
        if (instance.goal.get("predicate") or {}).get("subject") in lifted:
            return False
        return self.task.is_achieved(instance, scene)


def ran(message: dict) -> Instance:
    """The instance a trial's start event says the evaluator runs."""
    if "instance" not in message:
        raise OperatorError("the console's channel names no instance for its trials: run this with the same version")
    return Instance.from_json(message["instance"])


class Operator:
    """Answers one eval's console from its structured channel: `handle` takes one prompt and returns the line to
    type, as a person pressing keys does."""

    def __init__(self, plan: Plan, placement: PlacementClient, error: PlacementError, seed: int, on_flagged: str):
        self.plan, self.placement, self.error, self.on_flagged = plan, placement, error, on_flagged
        self.rng = np.random.default_rng(seed)
        self.index, self.instance = 0, None  # the trial being run, as the evaluator says it runs it
        self.moves: dict[str, tuple[float, float] | None] = {}  # object -> target (None: off the workspace)
        self.fixes = 0
        self.placed: list[dict] = []  # every placement made: object, target, where it was put
        self.resting: dict[str, float] = {}  # each object's height as staged, resting on the table
        self.said: list[str] = []  # what the operator reports beside its answers

    def handle(self, message: dict) -> str | None:
        """One message of the console's channel; returns what to type (a line) when it is a prompt."""
        prompt = message.get("prompt")
        if message.get("event") == "trial":
            self.index, self.instance = message["trial"], ran(message)
        if prompt == "stage":
            self.fixes = 0
            self.moves = {name: None if to is None else (to[0], to[1]) for name, to in message["moves"].items()}
            return self._stage()
        if prompt == "check":
            flagged = [name for name, off in message["off"].items() if off is None or off > 0]
            if self.on_flagged == "fix" and self.fixes < 2:
                self.fixes += 1
                self._place({name: self.moves[name] for name in flagged if name in self.moves})
                return ""
            return "a"
        if prompt == "call":  # the arm operator rings for a person: put each named object where it says
            self.said.append(f"called: {message['trouble']}")
            self._place({name: None if to is None else (to[0], to[1]) for name, to in message["fix"].items()})
            return ""
        if prompt == "label":
            return self._label()
        return "" if prompt == "aborted" else None

    def _stage(self) -> str:
        before = self.placement.scene()
        strays = self._strays(before)
        self._place({**self.moves, **strays})
        after, self.resting, _ = self.placement.look()
        moved = {name: pose.distance_to(after.objects[name]) for name, pose in before.objects.items()}
        each = ", ".join(f"{name} {distance:.3f}" for name, distance in moved.items() if distance > 0.001)
        self.said.append(f"moved {sum(moved.values()):.3f} m (the twin's truth: {each})")
        if strays:  # as a person who put back what the robot moved says so: what was moved, all told
            self.said.append(f"put back {', '.join(strays)}, which the console said to leave")
            return f"c {sum(moved.values()):.3f}"
        return ""

    def _label(self) -> str:
        scene, heights, gripped = self.placement.look()
        lifted = held(heights, self.resting, gripped)
        where = ", ".join(f"{name} ({pose.x:.3f}, {pose.y:.3f})" for name, pose in scene.objects.items())
        self.said.append(f"{ENDED}{where}")
        for name, up in lifted.items():
            self.said.append(held_line(name, up))
        return "y" if self.plan.judge(self.instance, scene, lifted) else "n"

    def _strays(self, seen: Scene) -> dict[str, tuple[float, float]]:
        """Objects the console says to leave that are not where the trial starts them (the robot moved them in the
        trial before, and no camera told the console): a person sees them and puts them back."""
        return {
            name: (pose.x, pose.y)
            for name, pose in self.instance.scene.objects.items()
            if name not in self.moves and name in seen.objects and seen.objects[name].distance_to(pose) > STRAY_M
        }

    def _place(self, targets: dict[str, tuple[float, float] | None]) -> None:
        for name, target in targets.items():
            if target is None:  # off the workspace: where the twin parks it
                parked = self.plan.parking[name]
                self.placement.place(name, parked.x, parked.y)
                continue
            dx, dy = self.error.draw(self.rng)
            self.placement.place(name, target[0] + dx, target[1] + dy)
            self.said.append(f"placed {name} {np.hypot(dx, dy) * 100:.1f} cm from its target")
            self.placed.append({"trial": self.index, "object": name, "target": target, "offset": [dx, dy]})
        if targets:
            time.sleep(SETTLE_S)


def main(argv: Sequence[str] | None = None) -> int:
    parser = ScriptParser(prog="python -m lerobot_contrast.twin.operator", description=__doc__.splitlines()[0])
    parser.add_argument("--placement", default=DEFAULT_ADDRESS, help="the twin's placement socket")
    parser.add_argument("--placement_error", default="none", help="none, normal:SIGMA or offset:D (metres)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the placement errors")
    parser.add_argument("--on_flagged", choices=("accept", "fix"), default="accept",
                        help="when the camera flags an object: accept it as placed, or place it again (twice at most)")  # fmt: skip
    known, eval_argv = parser.parse_known_args(argv)
    try:
        error = PlacementError.parse(known.placement_error)
        operator = Operator(Plan(eval_argv), PlacementClient(known.placement), error, known.seed, known.on_flagged)
        return run_answered(eval_argv, operator, (OperatorError,))
    except (OperatorError, UserError) as failure:
        print(f"error: {failure}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
