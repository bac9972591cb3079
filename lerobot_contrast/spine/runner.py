"""Execute trials on any LeRobot robot: stage the scene, run the policy at a fixed rate, judge or label the outcome.

With an operator console, a person stages each scene, may end or emergency-stop the episode, and labels
it. Without one (`--operator=auto`), the robot must implement `SceneIO`: the runner stages scenes and
judges outcomes from the scene itself, as in simulation.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Generator, Sequence
from contextlib import suppress
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

from lerobot_contrast.clock.robot_clock import robot_clock
from lerobot_contrast.contrast.cost import CostModel
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.staging import read_scene, reports_scene
from lerobot_contrast.contrast.task import Judgement, Task
from lerobot_contrast.contrast.trial import Outcome, TrialContext
from lerobot_contrast.operators.base import Label, Operator, SessionStopped, Staging
from lerobot_contrast.policies.base import Policy
from lerobot_contrast.record.observer import EpisodeObserver

try:
    from termios import error as TermiosError
except ImportError:  # no termios (Windows): pyserial raises its SerialException, an OSError, there
    TermiosError = OSError

if TYPE_CHECKING:
    from lerobot.robots import Robot

    from lerobot_contrast.record.shared_episodes import SharedEpisodes

# How an episode can end without a label: the operator stopped the robot, or the robot went away.
ABORTS = ("estop", "disconnected")
# The shortest pause between two tries to reconnect a lost robot.
RETRY_S = 0.5
# What a robot's own calls raise once its link is gone: a dropped network (ConnectionError, TimeoutError) or an
# unplugged serial adapter (pyserial's SerialException is an OSError; termios.error is not one).
LINK_ERRORS = (OSError, TermiosError)


class RobotLostError(UserError):
    pass


class _LinkLost(Exception):
    """A robot's own call failed with one of LINK_ERRORS (its `__cause__`); raised only around the robot's calls, so
    that an OSError from our own files (a full disk) is never taken for a lost robot."""


@dataclass
class Episode:
    steps: int
    path: list[Pose]
    duration_s: float
    ended_by: str  # predicate | success | failure | policy | max_steps | max_time | estop | disconnected


class RobotRunner:
    def __init__(
        self,
        robot: Robot,
        policy: Policy,
        task: Task,
        *,
        operator: Operator | None,
        fps: float | None,
        max_steps: int,
        max_episode_s: float | None = None,
        observers: Sequence[EpisodeObserver] = (),
        cost_unit: str = "m",
        cost_model: CostModel | None = None,
        reconnect_s: float = 5.0,
        say: Callable[[str], None] | None = None,
        shared: SharedEpisodes | None = None,
    ) -> None:
        self.scene_io = reports_scene(robot, task.storage_scene().objects)
        if operator is None and not self.scene_io:
            raise UserError(
                f"--operator=auto needs a robot that reports and stages its scene; {robot.name} cannot, "
                "so use --operator=console"
            )
        self.robot, self.policy, self.task, self.operator = robot, policy, task, operator
        self.period = 1.0 / fps if fps else 0.0
        self.max_steps, self.max_episode_s = max_steps, max_episode_s
        self.observers = list(observers)
        self.cost_unit = cost_unit
        self.cost_name = getattr(cost_model, "name", None)
        # A robot that stages its own scene and lets it settle in physics (`measures_staging`) is charged the metres
        # it reads back after settling, priced by the run's cost model, rather than the plan's poses.
        settles = getattr(robot, "measures_staging", False) and self.scene_io and operator is None
        self.read_back_cost = cost_model if settles and cost_model is not None and cost_model.unit == "m" else None
        # After a lost link, reconnecting is tried for `reconnect_s`, once per control period (at least every
        # RETRY_S); `say` tells the operator how long that takes.
        self.reconnect_s, self.say = reconnect_s, say
        self.pose_keys: tuple[str, str] | None = getattr(robot, "pose_keys", None)
        # Episodes end once the scene shows the goal, as the benchmark's do, where the scene can be read.
        self.stop_on_goal = self.scene_io and task.outcome == "predicate"
        # Why the session cannot go on (robot lost, operator stopped after an abort), raised at the next trial
        # so that the trial that ended this way is journalled first.
        self._halt: Exception | None = None
        self.shared = shared

    @property
    def _shares(self) -> bool:
        """Whether episodes come from and go to `shared`: only where nothing watches or stages them but the
        simulator itself (an episode taken from another cell has no frames to record)."""
        unattended = self.operator is None and self.scene_io and self.read_back_cost is None
        return self.shared is not None and unattended and not self.observers

    @property
    def halted(self) -> Exception | None:
        """Why the session cannot go on after the last trial (raised when the next one starts), if it cannot."""
        return self._halt

    def __call__(self, context: TrialContext) -> Outcome:
        return drive(self.trial(context), self.policy.act)

    def trial(self, context: TrialContext) -> Generator[dict[str, Any], dict[str, Any], Outcome]:
        """The trial as a generator: it yields each observation the policy must answer, is sent the action, and
        returns the outcome, so that a caller can step many trials side by side (lanes.py)."""
        if self._halt is not None:
            raise self._halt
        while True:
            staging = self._stage(context)
            if staging.action == "stop":
                raise SessionStopped("the operator stopped the session")
            if staging.action == "skip":
                return _skipped(context)
            shared = self.shared.get(context) if self._shares else None
            if shared is not None:  # another cell ran this very episode (record/shared_episodes.py)
                episode, scene_after = shared
            else:
                episode = yield from self._run_episode(context)
                if episode.ended_by in ABORTS:
                    return self._aborted(context, staging, episode)
                scene_after = self._scene_after(context, episode, staging)
                if self._shares:
                    self.shared.put(context, episode, scene_after)
            label = self._label(context, episode, scene_after)
            if label.action == "done":
                return self._finish(context, staging, episode, scene_after, label)
            for observer in self.observers:
                observer.discard()
            if label.action == "skip":
                return _skipped(context)
            if label.action == "stop":
                raise SessionStopped(
                    f"the operator stopped the session before labelling trial {context.index + 1}, which is not "
                    "recorded and runs again on resume"
                )
            # A redo is staged from where this attempt left things, so the console lists the moves from there.
            context = replace(context, current=scene_after)

    def _stage(self, context: TrialContext) -> Staging:
        bench = getattr(self.operator, "bench", None)
        if bench is not None:  # a calibrated camera shows the targets and measures the placement (staging/check.py)
            place = (lambda: self.robot.stage_scene(context.instance.scene)) if self.scene_io else None
            return bench.stage(self.robot, context, self.operator, place)
        staging = Staging("ready") if self.operator is None else self.operator.stage(context)
        if staging.action == "ready" and self.scene_io:  # in simulation the "operator's hands" place the objects
            self.robot.stage_scene(context.instance.scene)
            if self.read_back_cost is not None:
                staging = self._read_back(context, staging)
        return staging

    def _read_back(self, context: TrialContext, staging: Staging) -> Staging:
        """The staging as the robot reports it after settling: the metres objects moved from where the last trial
        left them, recorded as the calibrated bench records what it measured (staging/check.py)."""
        placed = read_scene(self.robot)
        moved = float(self.read_back_cost(context.current, placed))
        record = {
            "planned_cost": round(context.planned_cost, 4),
            "moved_m": round(moved, 4),
            "before": context.current.to_json()["objects"],
            "placed": {name: [round(p.x, 4), round(p.y, 4)] for name, p in placed.objects.items()},
        }
        return replace(staging, moved=moved, measured=record)

    def _run_episode(self, context: TrialContext) -> Generator[dict[str, Any], dict[str, Any], Episode]:
        self.policy.reset(context)
        features = {"observation": self.robot.observation_features, "action": self.robot.action_features}
        for observer in self.observers:
            observer.start(context, features, self.pose_keys)
        if self.operator is not None:
            self.operator.running()
        clock = robot_clock()  # real time, or the twin's simulated clock (--clock)
        start = clock.now()
        steps, path, ended_by, observation = 0, [], "max_steps", None
        try:
            observation = _robot_call(self.robot.get_observation)
            self._extend(path, observation)
            while steps < self.max_steps:
                tick = clock.now()
                ended_by = self._interrupted(tick - start, observation)
                if ended_by is not None:
                    break
                sent = _robot_call(self.robot.send_action, (yield observation))
                for observer in self.observers:
                    observer.step(tick - start, observation, sent)
                steps += 1
                observation = _robot_call(self.robot.get_observation)
                self._extend(path, observation)
                ended_by = self._finished(context)
                if ended_by is not None:
                    break
                clock.sleep(self.period - (clock.now() - tick))
            else:
                ended_by = "max_steps"
        except _LinkLost as lost:
            ended_by = "disconnected"
            self._recover(lost.__cause__, observation)
        return Episode(steps, path, clock.now() - start, ended_by)

    def _interrupted(self, elapsed: float, observation: dict[str, Any]) -> str | None:
        if self.max_episode_s is not None and elapsed >= self.max_episode_s:
            return "max_time"
        key = None if self.operator is None else self.operator.take_key()
        if key == "estop":
            self._hold(observation)
        return key

    def _finished(self, context: TrialContext) -> str | None:
        # A policy (or a robot, for a discrete "stop" action) can end its own episode, as VLN agents do.
        if getattr(self.policy, "done", False) or getattr(self.robot, "stop_requested", False):
            return "policy"
        if self.stop_on_goal and self.task.is_achieved(context.instance, _robot_call(read_scene, self.robot)):
            return "predicate"
        return None

    def _extend(self, path: list[Pose], observation: dict[str, Any]) -> None:
        if self.pose_keys is not None:
            x, y = self.pose_keys
            path.append(Pose(float(observation[x]), float(observation[y])))

    def _hold(self, observation: dict[str, Any] | None) -> None:
        """Stop at once: zero every velocity or delta, and hold every position where it was last observed. Where a
        position was never observed, nothing is safe to send (a 0 would drive that joint to 0 degrees)."""
        hold = {}
        for key in self.robot.action_features:
            if not key.endswith(".pos"):
                hold[key] = 0.0
            elif observation is not None and key in observation:
                hold[key] = float(observation[key])
            else:
                return
        _robot_call(self.robot.send_action, hold)

    def _recover(self, error: Exception, observation: dict[str, Any] | None) -> None:
        """After a lost connection: try to stop the robot, then to reconnect; record why not if it fails."""
        # The link is probably down already; these are best effort, reconnecting is what matters.
        with suppress(Exception):
            self._hold(observation)
        release(self.robot)
        if self.say is not None:
            self.say(
                f"the robot ({self.robot.name}) disconnected ({' '.join(str(error).split())}); "
                f"trying to reconnect for up to {self.reconnect_s:g} s"
            )
        deadline = time.monotonic() + self.reconnect_s
        while True:
            try:
                self.robot.connect()
                return
            except Exception as reconnect_error:
                error = reconnect_error
                _close_parts(self.robot)  # what the failed connect opened, or the next one is refused
            wait = max(self.period, RETRY_S)
            if time.monotonic() + wait > deadline:
                break
            time.sleep(wait)
        self._halt = RobotLostError(
            f"the robot ({self.robot.name}) disconnected and could not reconnect within {self.reconnect_s:g} s "
            f"({' '.join(str(error).split())}); check it, then continue the run"
        )

    def _scene_after(self, context: TrialContext, episode: Episode, staging: Staging) -> Scene:
        if self.scene_io:
            return read_scene(self.robot)
        robot = episode.path[-1] if episode.path else context.instance.scene.robot
        staged = Scene(dict(context.instance.scene.objects), robot)  # objects assumed where they were staged
        return self.operator.scene_after(self.robot, staged, staging)  # where a camera saw them, if one did

    def _label(self, context: TrialContext, episode: Episode, scene_after: Scene) -> Label:
        instance = context.instance
        judgement: Judgement | None = None
        if self.scene_io and self.task.outcome != "label":
            judgement = self.task.judge(instance, episode.path, scene_after)
        if self.operator is None:
            assert judgement is not None
            progress = judgement.progress if judgement.progress is not None else float(judgement.success)
            return Label("done", judgement.success, progress)
        early = episode.ended_by if episode.ended_by in ("success", "failure") else None
        return self.operator.label(self.task.subgoals(instance), judgement, early)

    def _cost(self, staging: Staging, label: Label | None = None) -> float | None:
        if self.operator is None:
            return staging.moved  # what a robot read back after settling its staging, else None: the plan's cost
        if self.cost_name == "robot_time":  # the arm staged: its own seconds, not a person's
            return staging.robot_s
        if self.cost_name == "interventions":
            return float(staging.interventions + int(label is not None and label.asked))
        if self.cost_unit == "s":
            return staging.reset_s
        return staging.moved

    def _finish(
        self, context: TrialContext, staging: Staging, episode: Episode, scene_after: Scene, label: Label
    ) -> Outcome:
        outcome = Outcome(
            success=label.success,
            steps=episode.steps,
            path_length=_length(episode.path),
            scene_after=scene_after,
            duration_s=episode.duration_s,
            progress=label.progress,
            reference_length=self.task.reference_length(context.instance),
            cost=self._cost(staging, label),
            extra={**self._extra(context, staging, episode), **_label_notes(label)},
        )
        return outcome

    def _aborted(self, context: TrialContext, staging: Staging, episode: Episode) -> Outcome:
        # After a lost link the scene is unknown (a restarted simulator is empty): assume it is as staged.
        scene_after = context.instance.scene
        if self.scene_io and episode.ended_by == "estop":
            scene_after = read_scene(self.robot)
        outcome = Outcome(
            success=False,
            steps=episode.steps,
            path_length=_length(episode.path),
            scene_after=scene_after,
            duration_s=episode.duration_s,
            status="aborted",
            cost=self._cost(staging),
            extra=self._extra(context, staging, episode),
        )
        asked = self.operator is not None and self._halt is None and episode.ended_by == "estop"
        if asked and self.operator.aborted("emergency stop").action == "stop":
            self._halt = SessionStopped("the operator stopped the session after an emergency stop")
        return outcome

    def _extra(self, context: TrialContext, staging: Staging, episode: Episode) -> dict[str, Any]:
        extra: dict[str, Any] = {
            "ended_by": episode.ended_by,
            **{k: v for k, v in self.task.path_metrics(context.instance, episode.path).items() if v is not None},
        }
        if self.operator is not None:
            extra["reset_s"] = round(staging.reset_s, 3)
            if staging.moved is not None:
                extra["moved_reported"] = staging.moved
            if staging.robot_s or staging.interventions:  # an operator that stages with the robot itself
                extra["robot_s"] = round(staging.robot_s, 3)
                extra["interventions"] = staging.interventions
        if staging.measured is not None:
            extra["staging"] = dict(staging.measured)
        return extra


def drive(trial: Generator[dict[str, Any], dict[str, Any], Outcome], act: Callable[[dict[str, Any]], dict]) -> Outcome:
    """Run a trial generator to its end, answering each observation with `act`."""
    try:
        observation = next(trial)
        while True:
            try:
                action = act(observation)
            except Exception as error:  # raised where the policy is asked, as if called inside the episode
                observation = trial.throw(error)
                continue
            observation = trial.send(action)
    except StopIteration as end:
        return end.value


def _robot_call(call: Callable[..., Any], *args: Any) -> Any:
    try:
        return call(*args)
    except LINK_ERRORS as error:
        raise _LinkLost() from error


def release(robot: Robot) -> Exception | None:
    """Disconnect a robot, lost or not, as far as it goes; returns why its `disconnect()` failed, if it did."""
    try:
        robot.disconnect()
        return None
    except Exception as error:
        _close_parts(robot)
        return error


def _close_parts(robot: Robot) -> None:
    """Close the bus port a robot left open. LeRobot's robots count themselves connected while their bus port is
    open, and a failed `disconnect()` (servos that no longer answer to have their torque disabled) or `connect()` (a
    handshake unanswered) leaves it open, so every `connect()` after it would refuse with "already connected".
    Cameras are left alone: closing LeRobot's zmq camera while its read thread still waits on the socket aborts the
    process inside libzmq (seen on the twin), which would lose the session's last words."""
    bus = getattr(robot, "bus", None)
    if _connected(bus):
        with suppress(Exception):
            bus.disconnect(disable_torque=False)  # a MotorsBus: only closes its port


def _connected(device: Any) -> bool:
    try:
        return bool(device is not None and device.is_connected)
    except Exception:  # a device too broken to say is treated as closed: connect() will tell
        return False


def _label_notes(label: Label) -> dict[str, bool]:
    """How a label came about, where not the usual way: a person asked by the arm, or none given yet; whether the
    audit drew the trial, and a person's own label of it where given at the bench."""
    said = (("label_asked", label.asked), ("unlabelled", label.unlabelled), ("audit_drawn", label.audit_drawn))
    notes = {key: True for key, flag in said if flag}
    return notes if label.audit is None else {**notes, "audit": label.audit}


def _skipped(context: TrialContext) -> Outcome:
    return Outcome(
        success=False, steps=0, path_length=0.0, scene_after=context.current, duration_s=0.0, status="skipped"
    )


def _length(path: list[Pose]) -> float:
    return sum(math.hypot(b.x - a.x, b.y - a.y) for a, b in zip(path, path[1:], strict=False))
