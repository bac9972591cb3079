"""The staging bench: show the operator each object's target on the camera view, then measure where the coloured
objects went, ask to fix or accept what is off, and say what was measured (placement, distance moved).

What a trial's staging measured is kept in `staging.json` in the run directory until the trial is journalled, so a
run killed mid-staging resumes with the effort already spent and the objects where they were measured.
"""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Callable, Mapping
from contextlib import nullcontext
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from lerobot_contrast.clock.robot_clock import robot_clock
from lerobot_contrast.contrast.cost import CostModel
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.staging import locate, overlay
from lerobot_contrast.staging.homography import CameraCalibration

MEMORY = "staging.json"
LIVE_PERIOD_S = 0.25  # the camera view refreshes this often while the operator stages


@dataclass(frozen=True)
class BenchGeometry:
    """What the bench knows of the task's table: its workspace, each checked object's colour, the objects' size."""

    bounds: tuple[tuple[float, float], tuple[float, float]]
    colours: Mapping[str, str]
    size: float  # footprint side and height of the objects, metres
    tray: tuple[tuple[float, float], tuple[float, float]] | None = None  # ((x_min, y_min), (x_max, y_max))

    def waiting(self, x: float, y: float) -> bool:
        """Whether an object seen at (x, y) waits in the tray: in view, but not on the workspace."""
        if self.tray is None:
            return False
        (x0, y0), (x1, y1) = self.tray
        return x0 <= x <= x1 and y0 <= y <= y1


class Bench:
    """Stages trials with a calibrated camera. `run_dir` (a callable, as the run directory is chosen after the
    console is built) says where to keep what staging measured."""

    def __init__(
        self,
        calibration: CameraCalibration,
        geometry: BenchGeometry,
        cost: CostModel,
        *,
        tolerance: float,
        measured_cost: bool,
        recording: Any,
        run_dir: Callable[[], Path | None],
    ) -> None:
        self.calibration, self.geometry, self.cost = calibration, geometry, cost
        self.tolerance, self.measured_cost = tolerance, measured_cost
        self.recording, self.run_dir = recording, run_dir
        # With a person's page: the last overlay drawn on the camera's frame, as JPEG, and how many were drawn.
        self.wants_picture = False
        self.picture: tuple[int, bytes] | None = None

    def frame(self, robot: Any) -> np.ndarray | None:
        """The camera's image of now (on a simulated clock, of a moment after whatever was just placed)."""
        robot_clock().look()
        return self._image(robot)

    def _image(self, robot: Any) -> np.ndarray | None:
        image = robot.get_observation().get(self.calibration.camera)
        return None if image is None else np.asarray(image)

    def measure(self, image: np.ndarray | None) -> dict[str, Pose]:
        if image is None:
            return {}
        found = locate.find_objects(
            image, self.calibration, self.geometry.colours, self.geometry.bounds, self.geometry.size
        )
        return {name: Pose(x, y) for name, (x, y) in found.items() if not self.geometry.waiting(x, y)}

    def stage(self, robot: Any, context: TrialContext, console: Any, place: Callable[[], None] | None) -> Any:
        """Stage `context`'s scene with the operator (`place`: a simulator's stand-in for their hands) and
        return the console's Staging, with what was measured."""
        memory = self._recall(context.index)
        seen = self.measure(self.frame(robot))
        before = memory["before"] if memory else _merged(context.current, seen)
        believed = _merged(context.current, seen if not memory else {**memory["placed"].objects, **seen})
        target = context.instance.scene
        self.show(robot, believed, target, None, _console_text(context))
        with self._live(robot):
            staging = console.stage(context)
        started = time.monotonic()
        while staging.action == "ready":
            if place is not None:
                place()
            image = self.frame(robot)
            seen = self.measure(image)
            placed = _merged(target, seen)
            off = self._off(target, seen)
            self._remember(context.index, before, placed)
            self.show(robot, placed, target, off, None, image)
            if not any(d is None or d > 0 for d in off.values()):
                console.say(f"staging check: {len(off)} coloured objects within {self.tolerance * 100:g} cm")
                return self._measured(context, staging, before, placed, off, started)
            answer = console.fix_or_accept(off, self.tolerance)
            if answer == "accept":
                return self._measured(context, staging, before, placed, off, started)
            if answer == "stop":
                return replace(staging, action="stop")
        return staging

    def scene_after(self, robot: Any, staged: Scene, measured: Mapping[str, Any]) -> Scene:
        """Where the episode left the objects: as the camera sees them now, else where staging measured them,
        else as planned (`staged`)."""
        placed = {name: Pose(x, y) for name, (x, y) in measured["placed"].items()}
        return _merged(_merged(staged, placed), self.measure(self.frame(robot)))

    def show(self, robot, believed: Scene, target: Scene, off, text: str | None, image=None) -> None:
        """The targets (and with `off`, how far each object is from its own) over the camera's frame: in the Rerun
        viewer (none with --staging.viewer=none), and as a picture for the person's page where there is one."""
        if self.recording is None and not self.wants_picture:
            return
        image = image if image is not None else self.frame(robot)
        marks = overlay.marks(self.calibration, believed, target, self.geometry.size, off)
        if self.recording is not None:
            overlay.log(self.recording, image, marks, text)
        if self.wants_picture and image is not None:
            drawn = cv2.cvtColor(overlay.draw(image, marks), cv2.COLOR_RGB2BGR)
            count = 1 if self.picture is None else self.picture[0] + 1
            self.picture = (count, cv2.imencode(".jpg", drawn, [cv2.IMWRITE_JPEG_QUALITY, 80])[1].tobytes())

    def show_seen(self, robot, target: Scene, text: str) -> None:
        """The targets over the camera's frame, each object's arrow from where the camera sees it now (one it does
        not see marked to bring in): what the arm's call for a person shows."""
        if self.recording is None and not self.wants_picture:
            return
        image = self.frame(robot)
        if image is None:
            return
        untracked = {name: pose for name, pose in target.objects.items() if name not in self.geometry.colours}
        believed = Scene({**untracked, **self.measure(image)}, target.robot)
        self.show(robot, believed, target, None, text, image)

    def _off(self, target: Scene, seen: Mapping[str, Pose]) -> dict[str, float | None]:
        """How far each checked object is from its target when past the tolerance (0.0: within it; None: not
        seen)."""
        off: dict[str, float | None] = {}
        for name, goal in target.objects.items():
            if name in self.geometry.colours:
                distance = seen[name].distance_to(goal) if name in seen else None
                off[name] = None if distance is None else (distance if distance > self.tolerance else 0.0)
        return off

    def _measured(self, context: TrialContext, staging, before: Scene, placed: Scene, off, started: float):
        moved = self.cost(before, placed)
        record = {
            "tolerance_m": self.tolerance,
            "planned_cost": round(context.planned_cost, 4),
            "moved_m": round(moved, 4),
            "before": before.to_json()["objects"],
            "placed": {name: [round(p.x, 4), round(p.y, 4)] for name, p in placed.objects.items()},
            "off_m": {name: None if d is None else round(d, 4) for name, d in off.items()},
            "accepted_off": sorted(name for name, d in off.items() if d is None or d > 0),
        }
        return replace(
            staging,
            reset_s=staging.reset_s + time.monotonic() - started,
            moved=moved if self.measured_cost else staging.moved,
            measured=record,
        )

    def _recall(self, index: int) -> dict[str, Scene] | None:
        path = self._memory_path()
        if path is None or not path.is_file():
            return None
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError):
            raise UserError(f"{path}: cannot read what the last staging measured; delete it to stage afresh") from None
        if data.get("trial") != index:  # another trial's: it was journalled, and its scene_after says the rest
            return None
        return {key: Scene.from_json({"objects": data[key]}) for key in ("before", "placed")}

    def _remember(self, index: int, before: Scene, placed: Scene) -> None:
        path = self._memory_path()
        if path is None:
            return
        data = {"trial": index, "before": before.to_json()["objects"], "placed": placed.to_json()["objects"]}
        temporary = path.with_suffix(".tmp")
        temporary.write_text(json.dumps(data) + "\n", encoding="utf-8")
        temporary.replace(path)

    def _memory_path(self) -> Path | None:
        run_dir = self.run_dir()
        return None if run_dir is None else Path(run_dir) / MEMORY

    def _live(self, robot: Any) -> _LiveView | nullcontext:
        return nullcontext() if self.recording is None else _LiveView(lambda: self.frame_to_rerun(robot))

    def frame_to_rerun(self, robot: Any) -> None:
        import rerun as rr

        image = self._image(robot)  # as it is: a simulated clock stays paused while a person stages
        if image is not None:
            self.recording.log("staging/camera", rr.Image(image))


class _LiveView:
    """Refresh the camera view on a thread while the operator stages; the thread stops before anything else
    uses the robot."""

    def __init__(self, refresh: Callable[[], None]) -> None:
        self.refresh = refresh
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True, name="staging-view")

    def __enter__(self) -> _LiveView:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop.set()
        self.thread.join()

    def _run(self) -> None:
        while not self.stop.wait(LIVE_PERIOD_S):
            try:
                self.refresh()
            except Exception:  # a frame missed while staging is harmless; the measurement reads its own
                continue


def _merged(scene: Scene, seen: Mapping[str, Pose]) -> Scene:
    """`scene` with the objects in `seen` where they were seen (their yaw as in `scene`)."""
    objects = dict(scene.objects)
    for name, pose in seen.items():
        yaw = objects[name].yaw if name in objects else 0.0
        objects[name] = Pose(pose.x, pose.y, yaw)
    return Scene(objects, scene.robot)


def _console_text(context: TrialContext) -> str:
    return f"**trial {context.index + 1}/{context.planned_trials}**: {context.instance.instruction}"
