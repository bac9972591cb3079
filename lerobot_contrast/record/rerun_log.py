"""One Rerun recording per episode (`rerun/episode_NNNNNN.rrd`): camera, top-down scene map, instruction and
perturbation, actions and state over time, outcome. JPEG encoding runs on a worker thread and everything is
sent in columns when the episode ends, so the control loop only copies each frame."""

from __future__ import annotations

import errno
import os
import re
import shutil
from collections.abc import Mapping, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from io import BytesIO
from pathlib import Path
from typing import Any

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
import rerun_bindings
from PIL import Image

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.perturbation import perturbation_label
from lerobot_contrast.contrast.task import Task
from lerobot_contrast.contrast.trial import TrialContext, TrialRecord
from lerobot_contrast.record.observer import EpisodeFiles
from lerobot_contrast.record.rerun_scene import MapBounds, instruction_markdown, log_map, outcome_markdown

APPLICATION_ID = "lerobot_contrast"  # no "/": Rerun 0.36+ rewrites such ids
RERUN_DIR = "rerun"
LAYOUT_FILE = "episode_layout.rbl"
FLUSH_TIMEOUT_S = 60.0
ROOM_SLACK_BYTES = 256 * 1024  # room for an episode's text, series and map beyond twice its images


class RerunWriteError(UserError):
    pass


def episode_path(run_dir: Path, index: int) -> Path:
    return run_dir / RERUN_DIR / f"episode_{index:06d}.rrd"


def camera_keys(features: Mapping[str, Any]) -> list[str]:
    """The robot's RGB cameras: observation features declared as (H, W, 3) shapes."""
    return [k for k, v in features.items() if isinstance(v, tuple) and len(v) == 3 and v[2] == 3]


def scalar_keys(features: Mapping[str, Any]) -> list[str]:
    return [k for k, v in features.items() if v is float]


def episode_views(cameras: list[str], bounds: MapBounds | None, prefix: str = "", name: str = "") -> rrb.Container:
    """The layout of one episode under entity `prefix`: cameras and map left, text and time series right."""
    spatial = [rrb.Spatial2DView(origin=f"{prefix}/camera/{cam}", name=f"{name}{cam}") for cam in cameras]
    map_view = rrb.Spatial2DView(
        origin=f"{prefix}/map",
        name=f"{name}map",
        visual_bounds=None if bounds is None else rrb.VisualBounds2D(x_range=bounds.x_range, y_range=bounds.y_range),
    )
    text = [
        rrb.TextDocumentView(origin=f"{prefix}/instruction", name=f"{name}instruction"),
        rrb.TextDocumentView(origin=f"{prefix}/outcome", name=f"{name}outcome"),
    ]
    series = [
        rrb.TimeSeriesView(origin=f"{prefix}/action", name=f"{name}action"),
        rrb.TimeSeriesView(origin=f"{prefix}/state", name=f"{name}state"),
    ]
    right = rrb.Vertical(*text, *series, row_shares=[3, 2, 2, 2])
    return rrb.Horizontal(rrb.Vertical(*spatial, map_view), right, column_shares=[3, 2])


def _jpeg(image: np.ndarray, quality: int) -> bytes:
    buffer = BytesIO()
    Image.fromarray(image).save(buffer, format="JPEG", quality=quality)
    return buffer.getvalue()


@dataclass
class _Episode:
    context: TrialContext
    cameras: list[str]
    state_keys: list[str]
    action_keys: list[str]
    pose_keys: tuple[str, str] | None
    times: list[float] = field(default_factory=list)
    state: list[list[float]] = field(default_factory=list)
    actions: list[list[float]] = field(default_factory=list)
    poses: list[tuple[float, float]] = field(default_factory=list)
    jpegs: dict[str, list[Future[bytes]]] = field(default_factory=dict)


class RerunEpisodeRecorder:
    """An `EpisodeObserver` writing one `.rrd` per episode into `run_dir/rerun/`.

    `task` (optional) supplies perturbation descriptions (`task.perturbations`) and the goal position shown on
    the map (`task.goal_position`)."""

    def __init__(self, run_dir: Path | str, task: Task | None = None, *, jpeg_quality: int = 75) -> None:
        self.run_dir = Path(run_dir)
        self.directory = self.run_dir / RERUN_DIR
        self.task = task
        self.jpeg_quality = jpeg_quality
        self.run_name = re.sub(r"[^A-Za-z0-9_-]+", "_", self.run_dir.resolve().name)
        self._encoder = ThreadPoolExecutor(max_workers=1, thread_name_prefix="rerun-jpeg")
        self._episode: _Episode | None = None

    def rollback(self, records: Sequence[TrialRecord]) -> None:
        kept = {self.run_dir / r.rerun_path for r in records if r.rerun_path is not None}
        for path in self.directory.glob("episode_*.rrd*"):  # also .partial: an episode cut off while saved
            if path not in kept:
                path.unlink()

    def start(self, context: TrialContext, features: dict[str, dict], pose_keys: tuple[str, str] | None) -> None:
        observation = features["observation"]
        cameras = camera_keys(observation)
        self._episode = _Episode(context, cameras, scalar_keys(observation), scalar_keys(features["action"]), pose_keys)
        self._episode.jpegs = {cam: [] for cam in cameras}

    def step(self, timestamp_s: float, observation: dict[str, Any], action: dict[str, Any]) -> None:
        episode = self._require_episode("step")
        episode.times.append(float(timestamp_s))
        episode.state.append([float(observation[k]) for k in episode.state_keys])
        episode.actions.append([float(action[k]) for k in episode.action_keys])
        if episode.pose_keys is not None:
            x, y = episode.pose_keys
            episode.poses.append((float(observation[x]), float(observation[y])))
        for cam in episode.cameras:
            # Copied here: a robot may reuse its frame buffer while the worker is still encoding.
            frame = np.array(observation[cam], dtype=np.uint8, copy=True)
            episode.jpegs[cam].append(self._encoder.submit(_jpeg, frame, self.jpeg_quality))

    def end(self, record: TrialRecord) -> EpisodeFiles:
        episode = self._require_episode("end")
        self._episode = None
        context = episode.context
        path = episode_path(self.run_dir, context.index)
        partial = path.with_name(path.name + ".partial")
        self.directory.mkdir(parents=True, exist_ok=True)
        _check_room(self.directory, episode.jpegs)
        bounds = MapBounds.around(context, episode.poses, record.scene_after, self.task)
        recording = rr.RecordingStream(APPLICATION_ID, recording_id=f"{self.run_name}-trial{context.index:06d}")
        try:
            _save_with_layout(recording, partial, rrb.Blueprint(episode_views(episode.cameras, bounds)))
            self._log_episode(recording, episode, record, bounds)
            recording.flush(timeout_sec=FLUSH_TIMEOUT_S)
            recording.disconnect()  # writes the footer; only then is the file complete
            os.replace(partial, path)
        except RuntimeError as error:  # Rerun's file writer stopped; why, it says only in its own log
            raise _write_failed(partial, error) from None
        finally:
            partial.unlink(missing_ok=True)
            del recording  # the last reference: only an unreferenced stream can be swept
            _sweep_closed_streams()
        self._write_layout(episode.cameras)
        return EpisodeFiles(rerun_path=path.relative_to(self.run_dir).as_posix())

    def discard(self) -> None:
        if self._episode is not None:
            for futures in self._episode.jpegs.values():
                for future in futures:
                    future.cancel()
        self._episode = None

    def close(self) -> None:
        self.discard()
        self._encoder.shutdown(wait=True)

    def _require_episode(self, method: str) -> _Episode:
        if self._episode is None:
            raise RuntimeError(f"RerunEpisodeRecorder.{method}() called outside an episode; call start() first")
        return self._episode

    def _log_episode(
        self, recording: rr.RecordingStream, episode: _Episode, record: TrialRecord, bounds: MapBounds
    ) -> None:
        context = episode.context
        recording.send_recording_name(
            f"trial {context.index} · {perturbation_label(context.instance.perturbation)} · {context.instance.id}"
        )
        _send_properties(recording, context, record)
        descriptions = _descriptions(self.task)
        unit = str(context.settings.get("cost_unit", ""))
        recording.log(
            "instruction",
            rr.TextDocument(instruction_markdown(context, descriptions, unit), media_type="text/markdown"),
            static=True,
        )
        recording.log(
            "outcome", rr.TextDocument(outcome_markdown(record, unit), media_type="text/markdown"), static=True
        )
        log_map(recording, context, episode.poses, record.scene_after, self.task, bounds)
        self._log_series(recording, episode)

    def _log_series(self, recording: rr.RecordingStream, episode: _Episode) -> None:
        n = len(episode.times)
        if n == 0:
            return
        indexes = [
            rr.TimeColumn("frame", sequence=np.arange(n)),
            rr.TimeColumn("time", duration=np.asarray(episode.times)),
        ]
        for entity, keys, values in (
            ("action", episode.action_keys, episode.actions),
            ("state", episode.state_keys, episode.state),
        ):
            if keys:
                recording.log(entity, rr.SeriesLines(names=keys), static=True)
                recording.send_columns(entity, indexes=indexes, columns=rr.Scalars.columns(scalars=np.asarray(values)))
        if episode.poses:
            positions = np.asarray(episode.poses)[:, ::-1]  # map coordinates: see rerun_scene.map_xy
            recording.send_columns("map/robot", indexes=indexes, columns=rr.Points2D.columns(positions=positions))
        for cam, futures in episode.jpegs.items():
            blobs = [future.result() for future in futures]
            recording.send_columns(
                f"camera/{cam}",
                indexes=indexes,
                columns=rr.EncodedImage.columns(blob=blobs, media_type=["image/jpeg"] * n),
            )

    def _write_layout(self, cameras: list[str]) -> None:
        """A blueprint file beside the episodes, for opening several of them with one layout."""
        layout = self.directory / LAYOUT_FILE
        if not layout.exists():
            rrb.Blueprint(episode_views(cameras, None)).save(APPLICATION_ID, layout)


def _save_with_layout(recording: rr.RecordingStream, path: Path, blueprint: rrb.Blueprint) -> None:
    """`recording.save(path, default_blueprint=blueprint)`, less its leak: Rerun holds a layout in a blueprint
    stream whose in-memory sink refers back to the stream, so that stream and its two threads live on for good
    unless disconnected, and `save` keeps no handle to it. This keeps one and disconnects it."""
    layout = rr.RecordingStream._from_native(
        rerun_bindings.new_blueprint(
            application_id=APPLICATION_ID, make_default=False, make_thread_default=False, default_enabled=True
        )
    )
    try:
        layout.set_time("blueprint", sequence=0)
        blueprint._log_to_stream(layout)
        memory = layout.memory_recording()
        rerun_bindings.save(
            path=str(path), default_blueprint=memory.storage, recording=recording.to_native(), write_footer=True
        )
    finally:
        layout.disconnect()


def _sweep_closed_streams() -> None:
    """Join the threads (a writer and a batcher) of every episode stream nothing references any more. Rerun keeps
    a dropped stream, threads and all, until the next `rr.init`; this is that sweep without a new global recording,
    and the process's own global recording (LeRobot's live view, say) is kept."""
    active = rr.get_global_data_recording()
    rerun_bindings.flush_and_cleanup_orphaned_recordings()  # also unsets the global recording
    if active is not None:
        rr.set_global_data_recording(active)


def _check_room(directory: Path, jpegs: dict[str, list[Future[bytes]]]) -> None:
    """Refuse to start an episode file the disk cannot hold: on a full disk Rerun may stall until its flush
    times out, or leave a file without its footer."""
    needed = 2 * sum(len(future.result()) for futures in jpegs.values() for future in futures) + ROOM_SLACK_BYTES
    if shutil.disk_usage(directory).free < needed:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(directory))


def _write_failed(partial: Path, error: RuntimeError) -> Exception:
    if shutil.disk_usage(partial.parent).free < ROOM_SLACK_BYTES:
        return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(partial))
    return RerunWriteError(
        f"{partial}: Rerun could not write the episode ({error}); check the disk, then resume the run"
    )


def _descriptions(task: Task | None) -> dict[str, str]:
    return {} if task is None else {p.name: p.description for p in task.perturbations}


def _send_properties(recording: rr.RecordingStream, context: TrialContext, record: TrialRecord) -> None:
    """Recording properties, so episodes can be found by instance, perturbation, policy and metric."""
    instance = context.instance
    settings = context.settings
    recording.send_property(
        "eval",
        rr.AnyValues(
            trial_index=context.index,
            instance_id=instance.id,
            base_id=instance.base_id,
            family=instance.family,
            perturbation=instance.perturbation or "original",
            perturbation_label=perturbation_label(instance.perturbation),
            axis=context.axis or "",
            staging=context.staging,
            strategy=str(settings.get("strategy", "")),
            policy=str(settings.get("policy", "")),
            task=str(settings.get("task", "")),
        ),
    )
    metrics = {"success": bool(record.success), "status": record.status, "steps": int(record.steps or 0)}
    metrics["cost"] = float(record.cost)
    metrics["progress"] = float(record.progress or 0.0)
    if record.spl is not None:
        metrics["spl"] = record.spl
    recording.send_property("metric", rr.AnyValues(**metrics))
