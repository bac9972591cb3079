"""Build the staging bench of a run: its calibration, what the task says of the table, and the live Rerun view."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.task import Task
from lerobot_contrast.staging.args import StagingArgs
from lerobot_contrast.staging.check import Bench, BenchGeometry
from lerobot_contrast.staging.homography import CameraCalibration, load
from lerobot_contrast.staging.locate import known_colour

VIEWERS = ("serve", "spawn", "none")


def default_calibration(task_ref: str) -> Path | None:
    """Where the calibration of a task file lives: beside the user's own task file, as <name>.calibration.json; for a
    shipped example, in LeRobot's calibration folder (HF_LEROBOT_CALIBRATION), as tables/<name>.calibration.json,
    since the installed package is no place for a user's files (and may be read-only or replaced on upgrade)."""
    from lerobot_contrast.domains.task_file.loader import examples_dir, task_file_path

    path = task_file_path(task_ref)
    if path is None:
        return None
    if path.resolve().parent == examples_dir().resolve():
        from lerobot.utils import constants  # read when called: HF_LEROBOT_CALIBRATION may be set by then

        return constants.HF_LEROBOT_CALIBRATION / "tables" / f"{path.stem}.calibration.json"
    return path.with_suffix(".calibration.json")


def geometry(task: Task, size: float) -> BenchGeometry:
    """The task's workspace bounds, its objects' colours (a task file's `colour`, else a Language-Table block's
    name, e.g. red_moon) and its tray."""
    spec, tray = getattr(task, "spec", None), None
    if spec is not None:
        area = spec.workspace.area
        bounds = ((area.x[0], area.y[0]), (area.x[1], area.y[1]))
        if spec.workspace.tray is not None:
            (x0, x1), (y0, y1) = spec.workspace.tray.box
            tray = ((x0, y0), (x1, y1))
        said = {n: o.attributes.get("colour", o.attributes.get("color")) for n, o in spec.objects.items()}
    else:
        from lerobot_contrast.domains.language_table import board

        bounds = board.WORKSPACE_BOUNDS
        said = {name: name.split("_")[0] for name in board.ALL_BLOCKS}
    colours = {name: known_colour(word) for name, word in said.items() if known_colour(word)}
    return BenchGeometry(bounds, colours, size, tray)


def pick_camera(calibrations: dict[str, CameraCalibration], robot: Any, path: Path) -> CameraCalibration:
    """The first calibrated camera the robot has."""
    features = getattr(robot, "observation_features", {})
    for name, calibration in calibrations.items():
        if name in features:
            return calibration
    raise UserError(
        f"{path}: calibrates cameras {', '.join(calibrations)} but the robot has {', '.join(map(str, features))}; "
        "calibrate this robot's camera with python -m lerobot_contrast.calibrate"
    )


def make_bench(
    args: StagingArgs, task_ref: str, task: Task, robot: Any, cost_name: str, run_dir: Callable[[], Path | None],
    recording: Any = None,
) -> Any:  # fmt: skip
    """The bench, or None where there is no calibration to stage with (then --cost=measured is refused). The
    apartment's (VLN) bench is its top-down map, with no camera to calibrate."""
    if args.viewer not in VIEWERS:
        raise UserError(f"--staging.viewer: unknown {args.viewer!r}; choose from: {', '.join(VIEWERS)}")
    from lerobot_contrast.domains.vln.task import VLNTask

    if isinstance(task, VLNTask):
        if cost_name == "measured":
            raise UserError("--cost=measured needs a table camera; the apartment has none, use --cost=distance")
        from lerobot_contrast.staging.apartment import MapBench

        return MapBench(recording or open_view(args.viewer))
    path = args.calibration or default_calibration(task_ref)
    if path is None or (args.calibration is None and not path.is_file()):
        if cost_name == "measured":
            raise UserError(
                f"--cost=measured needs a calibrated camera: run python -m lerobot_contrast.calibrate --task={task_ref} "
                "with your --robot flags, or give --staging.calibration=PATH"
            )
        return None
    calibration = pick_camera(load(path), robot, path)
    return Bench(
        calibration, geometry(task, args.object_size), task.cost_model("distance"), tolerance=args.tolerance,
        measured_cost=cost_name == "measured", recording=recording or open_view(args.viewer), run_dir=run_dir,
    )  # fmt: skip


def open_view(viewer: str) -> Any:
    """The Rerun recording the staging view is logged to (None: no view), and how the operator opens it."""
    import rerun as rr

    if viewer == "none":
        return None
    recording = rr.RecordingStream("lerobot_contrast_staging")
    if viewer == "serve":
        try:
            url = recording.serve_grpc()
        except Exception as error:  # the port is taken, most likely by another run's view
            raise UserError(
                f"--staging.viewer=serve: cannot serve the staging view ({' '.join(str(error).split())}); "
                "use --staging.viewer=spawn or none"
            ) from None
        print(f"staging view: run `rerun --connect {url}` in another terminal to see where each object goes")
    elif viewer == "spawn":
        recording.spawn()
        print("staging view: the Rerun viewer opens, showing where each object goes")
    return recording
