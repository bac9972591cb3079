"""What an episode's Rerun recording shows besides its streams: the top-down scene map (objects, goal, path,
differences from the base instance) and the instruction, perturbation and outcome as Markdown."""

from __future__ import annotations

import re
import zlib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import rerun as rr

from lerobot_contrast.contrast.cost import moved_objects
from lerobot_contrast.contrast.instance import Instance
from lerobot_contrast.contrast.perturbation import perturbation_label
from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.contrast.staging import staging_moves
from lerobot_contrast.contrast.task import Task, named_goal_position
from lerobot_contrast.contrast.trial import TrialContext, TrialRecord

AXIS_MEANING = {
    "L": "new wording, same behaviour",
    "LB": "new wording, different behaviour",
    "S": "scene change, same behaviour",
    "SB": "scene change, different behaviour",
}
NAMED_COLORS = {
    "red": (230, 80, 80),
    "blue": (90, 110, 235),
    "green": (70, 170, 70),
    "yellow": (220, 200, 60),
    "orange": (240, 150, 50),
    "purple": (160, 90, 200),
    "white": (235, 235, 235),
    "black": (60, 60, 60),
    "gray": (150, 150, 150),
    "grey": (150, 150, 150),
}
PALETTE = [(31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40), (148, 103, 189), (140, 86, 75)]
MOVED_TOLERANCE_M = 0.005  # displacements below this are placement noise, not a scene change


def map_xy(points: Iterable[tuple[float, float]]) -> np.ndarray:
    """Scene (x, y) to map coordinates: y to the right, x downwards (2-D views grow downwards).

    This is the Language-Table board as its instructions name it ("left" is -y, "top" is -x)."""
    array = np.asarray(list(points), dtype=np.float64).reshape(-1, 2)
    return array[:, ::-1]


def object_color(name: str, alpha: int = 255) -> tuple[int, int, int, int]:
    for word in re.split(r"[^a-z]+", name.lower()):
        if word in NAMED_COLORS:
            return (*NAMED_COLORS[word], alpha)
    return (*PALETTE[zlib.crc32(name.encode()) % len(PALETTE)], alpha)


@dataclass(frozen=True)
class MapBounds:
    x_range: tuple[float, float]
    y_range: tuple[float, float]

    @property
    def marker_radius(self) -> float:
        return 0.015 * max(self.x_range[1] - self.x_range[0], self.y_range[1] - self.y_range[0])

    @classmethod
    def around(
        cls,
        context: TrialContext,
        poses: list[tuple[float, float]],
        after: Scene,
        task: Task | None,
        margin: float = 0.1,
    ) -> MapBounds:
        scenes = (context.instance.scene, context.base.scene, after)
        points = [(p.x, p.y) for scene in scenes for p in scene.objects.values()] + list(poses)
        goal = _goal_position(task, context.instance)
        points += [goal] if goal is not None else []
        if not points:
            return cls((-1.0, 1.0), (-1.0, 1.0))
        uv = map_xy(points)
        low, high = uv.min(axis=0), uv.max(axis=0)
        pad = np.maximum((high - low) * margin, 0.05)
        return cls((low[0] - pad[0], high[0] + pad[0]), (low[1] - pad[1], high[1] + pad[1]))


def _points(scene: Scene) -> tuple[list[str], np.ndarray]:
    names = list(scene.objects)
    return names, map_xy((scene.objects[n].x, scene.objects[n].y) for n in names)


def log_map(
    recording: rr.RecordingStream,
    context: TrialContext,
    poses: list[tuple[float, float]],
    after: Scene,
    task: Task | None,
    bounds: MapBounds,
) -> None:
    """The static top-down map; the robot's per-frame position is logged with the other streams."""
    radius = bounds.marker_radius
    names, positions = _points(context.instance.scene)
    colors = [object_color(n) for n in names]
    recording.log("map/objects", rr.Points2D(positions, radii=radius, colors=colors, labels=names), static=True)
    names_after, after_xy = _points(after)
    recording.log(
        "map/objects_after",
        rr.Points2D(after_xy, radii=radius * 0.6, colors=[object_color(n, 110) for n in names_after]),
        static=True,
    )
    _log_base_changes(recording, context, radius)
    _log_goal(recording, context, task, radius)
    if poses:
        recording.log("map/path", rr.LineStrips2D([map_xy(poses)], colors=[(200, 200, 200)]), static=True)
        # Style of the robot's per-frame position, which is sent with the other streams.
        recording.log("map/robot", rr.Points2D.from_fields(radii=radius * 0.7, colors=[(255, 255, 255)]), static=True)


def _log_goal(recording: rr.RecordingStream, context: TrialContext, task: Task | None, radius: float) -> None:
    """The goal region, and an arrow to it from the object the instruction moves."""
    goal = _goal_position(task, context.instance)
    if goal is None:
        return
    gold = (255, 215, 0)
    block = context.instance.scene.objects.get(context.instance.goal.get("block"))
    recording.log(
        "map/goal",
        rr.Points2D(map_xy([goal]), radii=radius * 1.4, colors=[(*gold, 120)], labels=None if block else ["goal"]),
        static=True,
    )
    if block is not None:
        start = map_xy([(block.x, block.y)])
        recording.log(
            "map/goal_arrow",
            rr.Arrows2D(origins=start, vectors=map_xy([goal]) - start, colors=[gold], labels=["goal"]),
            static=True,
        )


def _log_base_changes(recording: rr.RecordingStream, context: TrialContext, radius: float) -> None:
    """Where the scene differs from the base instance: the base pose of each moved object, and an arrow to now."""
    base, scene = context.base.scene, context.instance.scene
    moved = [n for n in moved_objects(base, scene, MOVED_TOLERANCE_M) if n in base.objects and n in scene.objects]
    if not moved:
        return
    start = map_xy((base.objects[n].x, base.objects[n].y) for n in moved)
    end = map_xy((scene.objects[n].x, scene.objects[n].y) for n in moved)
    recording.log(
        "map/base_objects",
        rr.Points2D(start, radii=radius * 0.8, colors=[object_color(n, 70) for n in moved], labels=moved),
        static=True,
    )
    lengths = np.linalg.norm(end - start, axis=1)
    recording.log(
        "map/base_changes",
        rr.Arrows2D(origins=start, vectors=end - start, labels=[f"{d:.3f}" for d in lengths], colors=[(170, 170, 170)]),
        static=True,
    )


def _fmt_pose(pose: Pose | None) -> str:
    return "off the table" if pose is None else f"({pose.x:+.3f}, {pose.y:+.3f})"


def _fmt_value(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.3f}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_fmt_value(v) for v in value) + "]"
    return str(value)


def scene_changes(context: TrialContext) -> list[str]:
    """How this instance differs from its base: wording, goal fields, objects moved, added or removed."""
    base, instance = context.base, context.instance
    lines = []
    if instance.instruction != base.instruction:
        lines.append(f"instruction: “{base.instruction}” → “{instance.instruction}”")
    for key in sorted(set(base.goal) | set(instance.goal)):
        if key != "words" and base.goal.get(key) != instance.goal.get(key):
            lines.append(f"goal `{key}`: {_fmt_value(base.goal.get(key))} → {_fmt_value(instance.goal.get(key))}")
    for move in staging_moves(base.scene, instance.scene, MOVED_TOLERANCE_M):
        lines.append(f"`{move.name}` {_fmt_pose(move.start)} → {_fmt_pose(move.end)} ({move.distance:.3f} m)")
    return lines or ["nothing: this is the base instance as sampled"]


def instruction_markdown(context: TrialContext, descriptions: Mapping[str, str], unit: str) -> str:
    instance = context.instance
    label = perturbation_label(instance.perturbation)
    if instance.perturbation is None:
        perturbation = "none (an i.i.d. instance)"
    else:
        axis = context.axis or "?"
        detail = descriptions.get(instance.perturbation, "")
        perturbation = f"{label}, axis Δ{axis} ({AXIS_MEANING.get(axis, 'unknown axis')})" + (
            f": {detail}" if detail else ""
        )
    lines = [
        f"### Trial {context.index}: {label}",
        "",
        f"**Instruction:** {instance.instruction}",
        "",
        f"**Perturbation:** {perturbation}",
        "",
        "**Differs from the base instance in:**",
        *(f"- {line}" for line in scene_changes(context)),
        "",
        f"**Staging:** {context.staging}, planned cost {context.planned_cost:.3f} {unit}",
        *(
            f"- moved `{m.name}` {_fmt_pose(m.start)} → {_fmt_pose(m.end)} ({m.distance:.3f} m)"
            for m in staging_moves(context.current, instance.scene, MOVED_TOLERANCE_M)
        ),
        "",
        f"**Instance:** `{instance.id}` (base `{instance.base_id}`, family {instance.family})",
    ]
    return "\n".join(lines)


def outcome_markdown(record: TrialRecord, unit: str) -> str:
    verdict = ("success ✓" if record.success else "failure ✗") if record.status == "done" else record.status
    reference = record.reference_length
    rows = [
        ("steps", str(record.steps)),
        ("path length", f"{record.path_length:.3f}"),
        ("reference length", "-" if reference is None else f"{reference:.3f}"),
        ("SPL", "-" if record.spl is None else f"{record.spl:.3f}"),
        ("progress", "-" if record.progress is None else f"{record.progress:.2f}"),
        ("cost", f"{record.cost:.3f} {unit}".strip()),
        ("duration", f"{record.duration_s:.1f} s"),
    ]
    return "\n".join([f"### Outcome: {verdict}", "", "| | |", "|---|---|", *(f"| {k} | {v} |" for k, v in rows)])


def _goal_position(task: Task | None, instance: Instance) -> tuple[float, float] | None:
    return named_goal_position(instance) if task is None else task.goal_position(instance)
