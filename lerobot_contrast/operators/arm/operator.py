"""The arm as its own operator (`--operator=arm`): before each trial it looks at the table with the calibrated
camera, picks each object that is off target and puts it where the trial wants it, looks again and redoes what is
still off (a bounded number of rounds), and goes to rest; after the episode it lets go, withdraws, looks and labels
the trial with the task's own goal check. It calls a person (the console's bell, then Enter) only for what it cannot
do: an object not seen, out of reach, dropped twice, still off after its rounds, or a label it is unsure of.

It reads only what the bench reads: LeRobot's so101_follower (its servos and its camera) and the calibration."""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from lerobot_contrast.clock.robot_clock import robot_clock
from lerobot_contrast.contrast.audited import audited
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.task import Judgement
from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.operators.arm import joints as arm_joints
from lerobot_contrast.operators.arm.args import ArmArgs
from lerobot_contrast.operators.arm.memory import ArmMemory, Spent
from lerobot_contrast.operators.arm.verdict import verdict
from lerobot_contrast.operators.base import Label, SessionStopped, Staging
from lerobot_contrast.so101 import plan, reach
from lerobot_contrast.so101.motion import ArmMotion, Stopped
from lerobot_contrast.staging import seeing
from lerobot_contrast.staging.check import Bench

AIM_NEAR_M = 0.08  # earlier placements this near a target tell how the arm misses there
AIM_MAX_M = 0.03  # the most a target is corrected by: a larger miss is a fault to redo, not a bias


class ArmOperator:
    """`bench` is None: the arm checks its own staging. `person`: the console a person answers when called."""

    bench = None

    def __init__(
        self, robot: Any, task: Any, camera: Bench, person: Any, args: ArmArgs, memory: ArmMemory, seed: int = 0
    ) -> None:
        self.robot, self.task, self.camera, self.person, self.args = robot, task, camera, person, args
        self.seed = seed
        self.motion = ArmMotion(robot, plan.arm_model(task.spec), args.pace, self._stop_pressed, self._reached)
        self._staging = False  # while True, each waypoint reached keeps what staging has spent (a kill loses none)
        self._joints_known = False  # the joints' offsets measured (or recalled) this session
        self.size = camera.geometry.size
        self.memory = memory
        self.context: TrialContext | None = None
        self.after: seeing.View | None = None
        self.held_at_end: tuple[str, ...] = ()  # what the jaws held when the last episode ended
        self.landings: list[tuple[tuple[float, float], tuple[float, float]]] = []  # (aimed at, seen landing)
        self.attempts: list[dict[str, Any]] = []  # this trial's picks: each object, where from, aimed at, seen after
        self.calls = 0  # a person called to the bench, all session
        self._trial_calls = 0  # ... while staging this trial
        self._before, self._started, self._person_s = Spent(), 0.0, 0.0
        self._person_clock_s = 0.0  # the robot clock's seconds while a person was called (none on a simulated one)

    # --- the operator interface ---
    def stage(self, context: TrialContext) -> Staging:
        self.context = context
        self.person.announce(context)
        if self.args.measure_joints and not self._joints_known:
            try:
                self._measure_joints()
            except Stopped as stop:
                self.say(f"[bold red]{stop}[/]")
                return Staging("stop")
        self._before = self.memory.recall(context.index)  # a run killed mid-staging resumes with what it spent
        self._started, self._person_s, self._person_clock_s, self._trial_calls = robot_clock().now(), 0.0, 0.0, 0
        self.attempts = []
        try:
            self._staging = True
            with _link("staging"):
                self.motion.open_and_withdraw()
                rounds, view = self._place_all(context.instance.scene)
                self.motion.rest()
        except Stopped as stop:
            self.say(f"[bold red]{stop}[/]")
            self._checkpoint()
            return Staging("stop")
        finally:
            self._staging = False
        total = self._checkpoint()
        measured = self._record(context, view, rounds, total)
        return Staging("ready", total.person_s, measured=measured, robot_s=total.robot_s,
                       interventions=total.calls)  # fmt: skip

    def _measure_joints(self) -> None:
        """Each joint's calibration offset: measured earlier in this run, else now, before the run's first staging
        (its robot time is the session's, not a trial's)."""
        run_dir = self.memory.run_dir()
        fitted = arm_joints.recall(run_dir)
        if fitted is None:
            self.say("measuring the arm's joints: the jaws move through views of the workspace while the camera "
                     "finds the ball on the fixed jaw")  # fmt: skip
            with _link("measuring its joints"):
                fitted = arm_joints.measure(self.motion, lambda: self.camera.frame(self.robot), self.camera.calibration)
            arm_joints.keep(run_dir, fitted)
        self.motion.offsets = dict(fitted.offsets)
        self._joints_known = True
        offsets = ", ".join(f"{name} {math.degrees(value):+.1f}" for name, value in fitted.offsets.items())
        self.say(f"the arm's joints are off their model by (degrees): {offsets}; fitted to {fitted.views} views "
                 f"within {fitted.error_px:.1f} px")  # fmt: skip

    def _checkpoint(self) -> Spent:
        """What staging this trial has spent so far, kept in the run directory."""
        robot_s = robot_clock().now() - self._started - self._person_clock_s
        spent = self._before.add(robot_s, self._person_s, self._trial_calls)
        self.memory.keep(self.context.index, spent)
        return spent

    def fix_or_accept(self, off: Mapping[str, float | None], tolerance: float) -> str:
        return "accept"  # the arm measured its own staging; nothing else checks it

    def running(self) -> None:
        self.person.running()

    def take_key(self) -> str | None:
        return self.person.take_key()

    def aborted(self, reason: str) -> Label:
        return self.person.aborted(reason)

    def say(self, text: str) -> None:
        self.person.say(text)

    def scene_after(self, robot: Any, staged: Scene, staging: Staging) -> Scene:
        """Look at what the jaws hold where the episode ended them, then let go, withdraw out of view and look again:
        the scene the trial left, as the camera sees it. An object held when the episode ended was not put down,
        wherever it falls when the arm lets go."""
        self.person.note("ended")
        with _link("labelling"):
            self.held_at_end = tuple(name for name, seen in self._look().seen.items() if seen.held)
            self.motion.open_and_withdraw()
            self.after = self._look()
        return self.after.scene(staged)

    def label(self, subgoals: Sequence[str], suggestion: Judgement | None, early: str | None) -> Label:
        if early is not None and not subgoals:
            return Label("done", success=early == "success", progress=float(early == "success"))
        label = self._label(subgoals)
        if label.action != "done" or not audited(self.seed, self.context.index, self.args.audit):
            return label
        if self.args.audit_at == "viewer":
            self.say("[bold]audit[/]: this trial was drawn for a person's label too; give it on the run viewer's "
                     "audit page (python -m lerobot_contrast.view RUN_DIR)")  # fmt: skip
            return replace(label, audit_drawn=True)
        self.say("[bold]audit[/]: this trial was drawn for a person's label too; label it as you see it")
        checked = self.person.label(subgoals, None, None)  # no suggestion: the person's own eyes
        if checked.action != "done":
            return checked  # redo, skip or stop, as the person says
        return replace(label, audit=checked.success, audit_drawn=True)

    def _label(self, subgoals: Sequence[str]) -> Label:
        """The camera's label, or a person's where the camera is unsure."""
        instance, view = self.context.instance, self.after
        held = (*self.held_at_end, *(name for name, seen in view.seen.items() if seen.held))
        said = verdict(self.task.is_achieved, instance, view.scene(instance.scene), view.unseen, held,
                       self.args.uncertainty)  # fmt: skip
        self.person.note("labelled", success=said.success, sure=said.sure, held=list(held))
        if held:
            self.say(f"held in the jaws when the episode ended, not put down: {', '.join(held)}")
        if said.sure:
            self.say(f"the camera labels it: {'success' if said.success else 'failure'}")
            return Label("done", success=said.success, progress=float(said.success))
        if self.args.unsure == "unlabelled":
            self.say(f"unlabelled, for review: {said.why}")
            return Label("done", success=said.success, progress=float(said.success), unlabelled=True)
        self.say(f"[bold]the camera is unsure[/] ({said.why}): label it")
        self.calls += 1
        return replace(self.person.label(subgoals, Judgement(said.success), None), asked=True)

    # --- staging ---
    def _place_all(self, target: Scene) -> tuple[int, seeing.View]:
        """Rounds of pick-and-place until every seen object is within tolerance; a person for the rest. Returns the
        rounds and the last view."""
        dropped: dict[str, int] = {}
        view = self._look()
        for round_ in range(1, self.args.tries + 1):
            off = self._off(view, target)
            if not off:
                return round_ - 1, view
            trouble = self._move(off, view, target, dropped)
            view = self._look()
            if trouble:
                self._call(trouble, target)
                view = self._look()
        off = self._off(view, target)
        if off:
            self._call({name: "still off after the arm's tries" for name in off}, target)
            view = self._look()
        return self.args.tries, view

    def _off(self, view: seeing.View, target: Scene) -> dict[str, Pose | None]:
        """Objects to move: each coloured object off its target (or seen where the trial has none), with its target
        (None: take it off the workspace)."""
        off: dict[str, Pose | None] = {}
        for name in self.camera.geometry.colours:
            goal, seen = target.objects.get(name), view.seen.get(name)
            if goal is None and seen is not None:
                if name not in view.waiting:
                    off[name] = None
            elif goal is not None and not _inside(goal, self.camera.geometry.bounds):
                continue  # its place is off the workspace: the camera cannot check it there
            elif goal is not None and (
                seen is None or seen.held or Pose(seen.x, seen.y).distance_to(goal) > self.camera.tolerance
            ):
                off[name] = goal
        return off

    def _move(self, off, view: seeing.View, target: Scene, dropped: dict[str, int]) -> dict[str, str]:
        """Pick and place each object of `off` the camera sees, those whose target is free first; returns what
        needs a person, with why."""
        trouble: dict[str, str] = {}
        for name in _order(off, view):
            seen, goal = view.seen.get(name), off[name]
            if seen is None:
                trouble[name] = "not seen"
                continue
            if goal is None and self.camera.geometry.tray is None:
                trouble[name] = "to take off the workspace, and the task has no tray in the arm's reach"
                continue
            aim = self._tray_spot(name, view) if goal is None else self._aim(goal)
            others = [(at.x, at.y) for other, at in view.seen.items() if other != name and not at.held]
            try:
                steps = reach.pick_and_place(self.motion.model, self.motion.joints(), seen.pose(), self.size, aim,
                                             avoid=others)  # fmt: skip
            except reach.Unreachable:
                trouble[name] = "out of reach"
                continue
            self.motion.follow(steps)
            self._checkpoint()
            landed = self._look().seen.get(name)
            self.attempts.append({"object": name, "from": _rounded(seen.x, seen.y), "aim": _rounded(*aim),
                                  "landed": None if landed is None else _rounded(landed.x, landed.y),
                                  "held": landed is not None and landed.held})  # fmt: skip
            if landed is None or landed.held:
                dropped[name] = dropped.get(name, 0) + 1
                if dropped[name] >= 2:
                    trouble[name] = "dropped twice"
            elif math.dist(aim, (landed.x, landed.y)) <= AIM_MAX_M:
                self.landings.append((aim, (landed.x, landed.y)))
            # Further from its aim, it was pushed, not carried (a pick that missed): no measure of the aim, and the
            # next round picks it again from where it lies.
        return trouble

    def _aim(self, goal: Pose) -> tuple[float, float]:
        """Where to put an object down so that it lands on `goal`: the goal, moved by how far the camera saw earlier
        placements near it land from where they were aimed. A joint calibrated a few degrees off its model moves the
        jaws by an error that changes smoothly with the pose, so nearby placements share it (and the release's own
        slip); the camera measures it where the arm works, with no calibration motions of its own."""
        near = [(aim, landed) for aim, landed in self.landings if math.dist(aim, (goal.x, goal.y)) < AIM_NEAR_M]
        if not near:
            return goal.x, goal.y
        dx = float(np.mean([aim[0] - landed[0] for aim, landed in near]))
        dy = float(np.mean([aim[1] - landed[1] for aim, landed in near]))
        scale = min(1.0, AIM_MAX_M / max(math.hypot(dx, dy), 1e-9))
        return goal.x + scale * dx, goal.y + scale * dy

    def _tray_spot(self, name: str, view: seeing.View) -> tuple[float, float]:
        """Where in the tray to put `name` down: the spot furthest from everything else seen there."""
        (x0, y0), (x1, y1) = self.camera.geometry.tray
        half = self.size / 2
        xs = np.linspace(x0 + half, x1 - half, max(2, round((x1 - x0) / self.size)))
        ys = np.linspace(y0 + half, y1 - half, max(2, round((y1 - y0) / self.size)))
        others = [(at.x, at.y) for other, at in view.seen.items() if other != name and not at.held]
        spots = [(float(x), float(y)) for x in xs for y in ys]
        return max(spots, key=lambda spot: min((math.dist(spot, other) for other in others), default=0.0))

    def _call(self, trouble: Mapping[str, str], target: Scene) -> None:
        """Ring for a person to fix `trouble`, and wait for Enter; their time counts as theirs, not the robot's."""
        self._trial_calls += 1
        self.calls += 1
        self.motion.rest()
        started, started_clock = time.monotonic(), robot_clock().now()
        fix = {name: None if (goal := target.objects.get(name)) is None else [goal.x, goal.y] for name in trouble}
        said = "; ".join(f"{name}: {why}" for name, why in trouble.items())
        self.camera.show_seen(self.robot, target, f"a person is needed: {said}")
        answer = self.person.call(said, fix)
        self._person_s += time.monotonic() - started
        self._person_clock_s += robot_clock().now() - started_clock
        self._checkpoint()
        if answer == "stop":
            raise SessionStopped("the operator stopped the session while the arm asked for help")

    def _look(self) -> seeing.View:
        joints = self.motion.joints()
        image = self.camera.frame(self.robot)
        if image is None:
            raise CameraLost()
        jaws = self.motion.jaws(self.size, joints) if self.motion.holding(joints) else None
        return seeing.look(image, self.camera.calibration, self.camera.geometry, jaws, self.motion.links(joints))

    def _reached(self) -> None:
        if self._staging:
            self._checkpoint()

    def _stop_pressed(self) -> bool:
        return self.person.take_key() == "estop"

    def _record(self, context: TrialContext, view: seeing.View, rounds: int, total) -> dict[str, Any]:
        placed = view.scene(context.current)
        before = context.current
        return {
            "tolerance_m": self.camera.tolerance,
            "planned_cost": round(context.planned_cost, 4),
            "moved_m": round(float(self.camera.cost(before, placed)), 4),
            "before": before.to_json()["objects"],
            "placed": {name: [round(p.x, 4), round(p.y, 4)] for name, p in placed.objects.items()},
            "unseen": list(view.unseen),
            "rounds": rounds,
            "attempts": self.attempts,
            "robot_s": round(total.robot_s, 2),
            "person_calls": total.calls,
        }


class CameraLost(SessionStopped):
    """The camera sent no frame: the arm cannot see to stage or label."""

    def __init__(self) -> None:
        super().__init__("the camera stopped sending frames, so the arm cannot see to stage or label; check it")


class ArmLost(SessionStopped):
    """The arm stopped answering while it staged or labelled; what staging spent is kept for the resume."""


@contextlib.contextmanager
def _link(doing: str) -> Iterator[None]:
    """A lost serial link (pyserial's errors are OSErrors; LeRobot's bus raises ConnectionError) is one line."""
    try:
        yield
    except OSError as error:
        raise ArmLost(f"the arm stopped answering while {doing} ({' '.join(str(error).split())}); check it") from None


def _rounded(x: float, y: float) -> list[float]:
    """(x, y) in metres, rounded to the millimetre, for the journal."""
    return [round(x, 3), round(y, 3)]


def _inside(pose: Pose, bounds) -> bool:
    (x0, y0), (x1, y1) = bounds
    return x0 <= pose.x <= x1 and y0 <= pose.y <= y1


def _order(off: Mapping[str, Pose | None], view: seeing.View) -> list[str]:
    """Objects to move, those whose target another object to move still sits on last."""

    def blocked(name: str) -> bool:
        goal = off[name]
        return goal is not None and any(
            other != name and (seen := view.seen.get(other)) is not None
            and Pose(seen.x, seen.y).distance_to(goal) < 0.05
            for other in off
        )  # fmt: skip

    return sorted(off, key=blocked)
