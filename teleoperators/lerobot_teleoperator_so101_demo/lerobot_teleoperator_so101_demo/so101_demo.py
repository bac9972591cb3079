"""The scripted demonstrator as a LeRobot teleoperator: each episode it reads the twin's true scene, plans a
pick-and-place for the instruction and hands out the plan's joint goals in LeRobot's degrees as time passes."""

from __future__ import annotations

import logging
import sys
import time
from typing import Any

from lerobot.teleoperators.teleoperator import Teleoperator

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.domains.task_file import load_task_file
from lerobot_contrast.so101 import arm, plan
from lerobot_contrast.twin.placement_client import PlacementClient, TwinError
from lerobot_teleoperator_so101_demo.config_so101_demo import SO101DemoConfig

DEFAULT_EPISODE_S = 60.0  # lerobot-record's own default for --dataset.episode_time_s
# lerobot-record calls get_action without pause within an episode and its reset period, then saves the episode
# (writing its files takes longer than this): a pause this long after the episode's time means the next one began.
SAVE_PAUSE_S = 0.3


def record_flag(name: str) -> str | None:
    """The value of lerobot-record's `--dataset.NAME` on this process's command line, if given."""
    flag, argv = f"--dataset.{name}", sys.argv[1:]
    for k, arg in enumerate(argv):
        if arg.startswith(flag + "="):
            return arg.split("=", 1)[1]
        if arg == flag and k + 1 < len(argv):
            return argv[k + 1]
    return None


class SO101Demo(Teleoperator):
    """Puts the instructed object where the instruction says, on the twin; places the objects anew through the
    twin's placement socket when it connects and at each reset period."""

    config_class = SO101DemoConfig
    name = "so101_demo"

    def __init__(self, config: SO101DemoConfig):
        super().__init__(config)
        self.config = config
        self.instruction = config.instruction or record_flag("single_task")
        self.episode_time_s = config.episode_time_s or float(record_flag("episode_time_s") or DEFAULT_EPISODE_S)
        self.episode = config.first_episode  # the placement to make next
        self._placement: PlacementClient | None = None
        self._placed = False  # the objects are placed for the coming episode
        self._start = self._last = None
        self._schedule: list[tuple[float, dict[str, float]]] = []

    @property
    def action_features(self) -> dict[str, type]:
        return {f"{name}.pos": float for name in arm.MOTOR_NAMES}

    @property
    def feedback_features(self) -> dict:
        return {}

    @property
    def is_connected(self) -> bool:
        return self._placement is not None

    @property
    def is_calibrated(self) -> bool:
        return True  # nothing physical to calibrate

    def calibrate(self) -> None:
        pass

    def configure(self) -> None:
        pass

    def connect(self, calibrate: bool = True) -> None:
        if not self.instruction:
            raise UserError("so101_demo needs an instruction: give --dataset.single_task or --teleop.instruction")
        self.task = load_task_file(self.config.task)
        self.predicate = plan.goal_of(self.task, self.instruction)
        self.model = plan.arm_model(self.task.spec)
        self._placement = PlacementClient(self.config.placement)
        try:
            self.place_anew()
        except UserError:
            self.disconnect()
            raise

    def disconnect(self) -> None:
        self._placement = None

    def send_feedback(self, feedback: dict[str, Any]) -> None:
        pass  # the plan needs no feedback: the twin's servos reach each goal before the next

    def ask(self, request: dict) -> dict:
        """The twin's reply to a placement request; a twin that does not answer or refuses is one line."""
        try:
            return self._placement.ask(request)
        except TwinError as error:
            raise UserError(f"so101_demo: {error}") from None

    def place_anew(self) -> None:
        """Put the objects where this episode's seeded placement has them."""
        for name, (x, y, yaw) in plan.placement(self.task.spec, self.config.seed, self.episode).items():
            self.ask({"cmd": "place", "object": name, "x": x, "y": y, "yaw": yaw})
        self.episode += 1
        self._placed = True

    def begin_episode(self, now: float) -> None:
        """Plan this episode's motion from the true scene (the arm at rest)."""
        if not self._placed:  # no reset period (--dataset.reset_time_s=0): place now
            self.place_anew()
        reply = self.ask({"cmd": "scene"})
        poses = {name: (x, y, reply["z"][name], yaw) for name, (x, y, yaw) in reply["objects"].items()}
        self._schedule = plan.schedule(self.model, self.predicate, poses, self.task.spec, self.config.pace)
        self._start, self._placed = now, False
        if self.schedule_s > self.episode_time_s:
            logging.warning(
                "so101_demo: the motion takes %.1f s, longer than the %.1f s episode: give a longer "
                "--dataset.episode_time_s or a smaller --teleop.pace",
                self.schedule_s,
                self.episode_time_s,
            )

    @property
    def schedule_s(self) -> float:
        """How long this episode's motion takes (0: it stays at rest)."""
        return self._schedule[-1][0] if self._schedule else 0.0

    def get_action(self) -> dict[str, float]:
        now = time.monotonic()
        if self._start is None:
            self.begin_episode(now)
        elif now - self._start >= self.episode_time_s:  # the reset period, or the next episode after a save
            if now - self._last > SAVE_PAUSE_S:
                self.begin_episode(now)
            elif not self._placed:
                self.place_anew()
        self._last = now
        return plan.goals_at(self._schedule, now - self._start)
