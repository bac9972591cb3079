"""What the operator sees while staging: each object's target outline and an arrow from where it is believed to be,
labelled, drawn on the camera frame (in Rerun, or with OpenCV for a still picture)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import cv2
import numpy as np

from lerobot_contrast.contrast.scene import Pose, Scene
from lerobot_contrast.staging.homography import CameraCalibration

COLOURS = {"move": (255, 170, 0), "stay": (160, 160, 160), "ok": (40, 220, 40), "off": (255, 40, 40)}


@dataclass(frozen=True)
class Mark:
    """One object's overlay, in pixels."""

    name: str
    outline: np.ndarray | None  # (5, 2) closed footprint at the target (None: the object leaves the workspace)
    start: np.ndarray | None  # where the object is believed (or measured) to be
    end: np.ndarray | None  # its target's centre
    label: str
    state: str  # move | stay | ok | off


def footprint(pose: Pose, size: float | tuple[float, float]) -> np.ndarray:
    """The closed outline (5, 2) of a `size` square, or a (length along yaw, width) box, at `pose` (metres)."""
    length, width = (size, size) if isinstance(size, float | int) else size
    hl, hw = length / 2, width / 2
    corners = np.array([[-hl, -hw], [hl, -hw], [hl, hw], [-hl, hw], [-hl, -hw]])
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    return corners @ np.array([[c, s], [-s, c]]) + (pose.x, pose.y)


def marks(
    calibration: CameraCalibration,
    believed: Scene,
    target: Scene,
    size: float | Mapping[str, tuple[float, float]],
    off: Mapping[str, float | None] | None = None,
) -> list[Mark]:
    """The overlay of staging `target` from `believed`, objects `size` (a side, or each one's length and width);
    with `off` (metres past the tolerance, by checked object), targets are marked ok or off instead."""
    result = []
    for name in sorted(set(believed.objects) | set(target.objects)):
        start, end = believed.objects.get(name), target.objects.get(name)
        extent = size if isinstance(size, float | int) else size[name]
        moved = start is None or end is None or start.distance_to(end) > float(np.min(extent)) / 4
        state = "move" if moved else "stay"
        if off is not None and name in off:
            state = "off" if off[name] is None or off[name] > 0 else "ok"
        result.append(
            Mark(
                name,
                None if end is None else calibration.to_pixels(footprint(end, extent)),
                None if start is None else calibration.to_pixels(np.array([[start.x, start.y]]))[0],
                None if end is None else calibration.to_pixels(np.array([[end.x, end.y]]))[0],
                _label(name, start, end, state, None if off is None else off.get(name)),
                state,
            )
        )
    return result


def _label(name: str, start: Pose | None, end: Pose | None, state: str, off: float | None) -> str:
    if state in ("ok", "off"):
        return f"{name}: {'ok' if off == 0 else 'not seen' if off is None else f'{off * 100:.1f} cm off'}"
    if end is None:
        return f"{name}: take away"
    if start is None:
        return f"{name}: bring in"
    return f"{name} {start.distance_to(end):.2f} m" if state == "move" else name


def draw(image: np.ndarray, overlay: list[Mark]) -> np.ndarray:
    """A copy of the RGB `image` with the overlay drawn in, for a still picture (the docs, a saved frame)."""
    out = image.copy()
    scale = max(1.0, image.shape[1] / 640)
    for mark in overlay:
        colour = COLOURS[mark.state]
        if mark.outline is not None:
            cv2.polylines(out, [np.round(mark.outline).astype(np.int32)], True, colour, round(2 * scale), cv2.LINE_AA)
        if mark.start is not None and mark.end is not None and mark.state == "move":
            start, end = tuple(np.round(mark.start).astype(int)), tuple(np.round(mark.end).astype(int))
            tip = min(0.3, 12 * scale / max(1.0, float(np.linalg.norm(mark.end - mark.start))))  # a tip of ~12 px
            cv2.arrowedLine(out, start, end, colour, round(2 * scale), cv2.LINE_AA, tipLength=tip)
        if mark.state == "stay":  # only its outline: the picture names what to move
            continue
        anchor = mark.end if mark.end is not None else mark.start
        x, y = np.round(anchor + (6 * scale, -6 * scale)).astype(int)
        cv2.putText(out, mark.label, (x, y), cv2.FONT_HERSHEY_SIMPLEX, 0.4 * scale, (0, 0, 0), round(3 * scale))
        cv2.putText(out, mark.label, (x, y), cv2.FONT_HERSHEY_SIMPLEX, 0.4 * scale, colour, round(scale))
    return out


def log(
    recording, image: np.ndarray | None, overlay: list[Mark], text: str | None = None, entity: str = "staging/camera"
) -> None:
    """Log the frame (the camera's, or a map) and the overlay on it to the Rerun `recording`, under `entity`."""
    import rerun as rr

    if image is not None:
        recording.log(entity, rr.Image(image))
    outlines = [m for m in overlay if m.outline is not None]
    recording.log(
        f"{entity}/targets",
        rr.LineStrips2D(
            [m.outline for m in outlines], colors=[COLOURS[m.state] for m in outlines], labels=[m.label for m in outlines],
            radii=1.0, show_labels=True,
        ),
    )  # fmt: skip
    arrows = [m for m in overlay if m.start is not None and m.end is not None and m.state == "move"]
    recording.log(
        f"{entity}/arrows",
        rr.Arrows2D(
            origins=[m.start for m in arrows], vectors=[m.end - m.start for m in arrows],
            colors=[COLOURS[m.state] for m in arrows], labels=[m.name for m in arrows], radii=1.0,
        ),
    )  # fmt: skip
    if text is not None:
        recording.log("staging/console", rr.TextDocument(text, media_type=rr.MediaType.MARKDOWN))
