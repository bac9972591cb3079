"""Staging the apartment for the LoCoBot: there is no table camera, so the operator sees the top-down map with each
piece of furniture's target outline and an arrow from where the plan believes it is. Nothing is measured."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from lerobot_contrast.contrast.scene import Scene
from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.domains.vln.apartment.furniture import furniture_for
from lerobot_contrast.domains.vln.apartment.geometry import Footprints, Room
from lerobot_contrast.domains.vln.apartment.topdown import render_map
from lerobot_contrast.staging import overlay
from lerobot_contrast.staging.homography import CameraCalibration

PX_PER_M = 60.0
MARGIN_PX = 10  # render_map's border around the room


def map_frame(room: Room, believed: Scene) -> tuple[np.ndarray, CameraCalibration]:
    """The map of the furniture where the plan believes it is, and the metres-to-map-pixels transform (as a
    calibration, so the table's overlay code draws on it)."""
    image = render_map(room, Footprints.from_objects(believed.objects), robot=believed.robot, px_per_m=PX_PER_M)
    height, width = image.shape[:2]
    to_pixels = np.array([[PX_PER_M, 0, MARGIN_PX], [0, -PX_PER_M, height - MARGIN_PX], [0, 0, 1]], float)
    return image, CameraCalibration("map", (width, height), to_pixels, 0.0, 0)


def map_marks(room: Room, believed: Scene, target: Scene) -> tuple[np.ndarray, list[overlay.Mark]]:
    image, to_pixels = map_frame(room, believed)
    names = set(believed.objects) | set(target.objects)
    sizes = {name: (furniture_for(name).length, furniture_for(name).width) for name in names}
    return image, overlay.marks(to_pixels, believed, target, sizes)


class MapBench:
    """Shows the map overlay while the operator stages; the console's list of moves and its prompts are as without it."""

    def __init__(self, recording: Any, room: Room | None = None) -> None:
        self.recording, self.room = recording, room or Room()

    def stage(self, robot: Any, context: TrialContext, console: Any, place: Callable[[], None] | None) -> Any:
        if self.recording is not None:
            image, marks = map_marks(self.room, context.current, context.instance.scene)
            text = f"**trial {context.index + 1}/{context.planned_trials}**: {context.instance.instruction}"
            overlay.log(self.recording, image, marks, text, entity="staging/map")
        staging = console.stage(context)
        if staging.action == "ready" and place is not None:
            place()
        return staging
