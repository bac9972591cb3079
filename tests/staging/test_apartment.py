"""The apartment's staging overlay for the LoCoBot: furniture targets drawn on the top-down map."""

import io

import cv2
import numpy as np
import rerun as rr
from rerun.experimental import RrdReader
from rich.console import Console

from lerobot_contrast.contrast.scene import Pose
from lerobot_contrast.contrast.trial import TrialContext
from lerobot_contrast.domains import load_task
from lerobot_contrast.domains.vln.apartment.furniture import furniture_for
from lerobot_contrast.domains.vln.apartment.geometry import Room
from lerobot_contrast.operators.console import Answers, OperatorConsole
from lerobot_contrast.staging.apartment import MapBench, map_frame, map_marks


def test_furniture_targets_land_where_the_map_draws_that_furniture(tmp_path):
    believed = load_task("vln").storage_scene()
    target = believed.with_object("chair", Pose(6.0, 3.0, 0.5))
    _, marks = map_marks(Room(), believed, target)
    chair = next(m for m in marks if m.name == "chair")
    assert chair.state == "move" and chair.label.startswith("chair ") and chair.label.endswith(" m")
    assert {m.state for m in marks if m.name != "chair"} == {"stay"}
    staged, _ = map_frame(Room(), target)  # the map once the chair is where it should go
    inside = np.zeros(staged.shape[:2], np.uint8)
    cv2.fillPoly(inside, [np.round(chair.outline).astype(np.int32)], 1)
    is_chair = np.all(staged == furniture_for("chair").color, axis=2)
    assert is_chair[inside > 0].mean() > 0.6  # the outline is the chair's footprint once it stands there
    assert is_chair[inside == 0].sum() < 0.1 * is_chair.sum()


def test_the_map_bench_shows_the_map_and_leaves_staging_to_the_console(tmp_path):
    task = load_task("vln")
    instance = task.sample(1, np.random.default_rng(0))[0]
    context = TrialContext(
        index=0, instance=instance, base=instance, current=task.storage_scene(), planned_cost=1.0, staging="reset",
        rng=np.random.default_rng(0), planned_trials=1,
    )  # fmt: skip
    view = rr.RecordingStream("lerobot_contrast_staging")
    logged = view.memory_recording()
    console = OperatorConsole(Answers(io.StringIO("\n")), Console(file=io.StringIO()))
    placed = []
    staging = MapBench(view).stage(None, context, console, lambda: placed.append(True))
    assert staging.action == "ready" and staging.measured is None and placed == [True]
    (tmp_path / "view.rrd").write_bytes(logged.drain_as_bytes())
    entities = {chunk.entity_path for chunk in RrdReader(str(tmp_path / "view.rrd")).stream().to_chunks()}
    assert {"/staging/map", "/staging/map/targets", "/staging/map/arrows", "/staging/console"} <= entities
