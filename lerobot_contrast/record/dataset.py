"""Every trial as an episode of a LeRobotDataset v3 in `run_dir/dataset/`, with per-frame `eval.*` columns,
`next.success` on the last frame and a contrast-set sidecar in `meta/contrast_eval/`. Frames are buffered while
the episode runs and handed to LeRobot (validation, video encoding) when it ends, so the control loop only
builds and copies each frame and no encoder competes with it for the CPU. Each saved episode's files are closed at
once, so a run killed at any point keeps every episode it finished, and the dataset stays open for the next."""

from __future__ import annotations

import functools
import importlib
import json
import os
import re
import shutil
from collections.abc import Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any

import datasets
import numpy as np
from lerobot.datasets import LeRobotDataset
from lerobot.utils.feature_utils import build_dataset_frame, hw_to_dataset_features

from lerobot_contrast.contrast.trial import TrialContext, TrialRecord
from lerobot_contrast.record.dataset_rollback import RESTORE, DatasetError, roll_back
from lerobot_contrast.record.observer import EpisodeFiles

DATASET_DIR = "dataset"
SIDECAR_DIR = "meta/contrast_eval"
SIDECAR_VERSION = 1
# Run files copied into the sidecar when the dataset is closed: together they rebuild the plan.
RUN_FILES = ("config.json", "plan.json", "summary.json")
FULL_MB = 1e-6  # LeRobot's file-size limit that every file reaches: one episode per file
EVAL_FEATURES = {
    "eval.instance_id": {"dtype": "string", "shape": (1,), "names": None},
    "eval.base_id": {"dtype": "string", "shape": (1,), "names": None},
    "eval.perturbation": {"dtype": "string", "shape": (1,), "names": None},
    "eval.trial_index": {"dtype": "int64", "shape": (1,), "names": None},
    "next.success": {"dtype": "bool", "shape": (1,), "names": None},
    "next.done": {"dtype": "bool", "shape": (1,), "names": None},
}


@functools.cache
def video_backend() -> str:
    """torchcodec where it loads (it needs FFmpeg's shared libraries), else PyAV: decided once per process, so
    LeRobot does not retry torchcodec, and warn about it, on every episode."""
    try:
        importlib.import_module("torchcodec.decoders")
    except (ImportError, OSError, RuntimeError):
        return "pyav"
    return "torchcodec"


def dataset_features(features: dict[str, dict], use_videos: bool) -> dict[str, dict]:
    """LeRobot dataset features for a robot's observation and action features, plus the eval columns."""
    return {
        **hw_to_dataset_features(features["observation"], "observation", use_videos),
        **hw_to_dataset_features(features["action"], "action", use_videos),
        **EVAL_FEATURES,
    }


class DatasetRecorder:
    """An `EpisodeObserver` recording every trial into the run's LeRobotDataset.

    The dataset is created at the first episode (its features come from the robot), or, when `run_dir`
    already holds one with N episodes, resumed so the next episode is number N."""

    def __init__(
        self,
        run_dir: Path | str,
        *,
        fps: int,
        repo_id: str | None = None,
        robot_type: str | None = None,
        use_videos: bool = True,
        max_buffer_mb: float = 512.0,
    ) -> None:
        self.run_dir = Path(run_dir)
        self.root = self.run_dir / DATASET_DIR
        self.fps = int(fps)
        self.repo_id = repo_id or "local/" + re.sub(r"[^A-Za-z0-9_.-]+", "_", self.run_dir.resolve().name)
        self.robot_type = robot_type
        self.use_videos = use_videos
        self.max_buffer_bytes = int(max_buffer_mb * 2**20)
        self.dataset: LeRobotDataset | None = None
        self._worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="dataset-frames")
        self._futures: list[Future[None]] = []
        self._context: TrialContext | None = None
        self._features: dict[str, dict] = {}
        self._image_keys: list[str] = []
        self._pending: dict[str, Any] | None = None
        self._buffer: list[dict[str, Any]] = []
        self._buffered_bytes = 0
        self._frames = 0

    def rollback(self, records: Sequence[TrialRecord]) -> None:
        episodes = [r.dataset_episode for r in records if r.dataset_episode is not None]
        roll_back(self.root, max(episodes, default=-1) + 1)

    def start(self, context: TrialContext, features: dict[str, dict], pose_keys: tuple[str, str] | None) -> None:
        wanted = dataset_features(features, self.use_videos)
        if self.dataset is None:
            self.dataset = self._open(wanted)
        self._features = wanted
        self._image_keys = [k for k, v in wanted.items() if v["dtype"] in ("video", "image")]
        self._context = context
        self._pending, self._futures, self._buffer, self._buffered_bytes, self._frames = None, [], [], 0, 0

    def step(self, timestamp_s: float, observation: dict[str, Any], action: dict[str, Any]) -> None:
        context = self._require_context("step")
        frame = {
            **build_dataset_frame(self._features, observation, "observation"),
            **build_dataset_frame(self._features, action, "action"),
        }
        for key in self._image_keys:
            frame[key] = np.array(frame[key], copy=True)  # the robot may reuse its frame buffer
        instance = context.instance
        frame.update(
            {
                "task": instance.instruction,
                "eval.instance_id": instance.id,
                "eval.base_id": instance.base_id,
                "eval.perturbation": instance.perturbation or "original",
                "eval.trial_index": np.array([context.index], dtype=np.int64),
            }
        )
        # Held back one step: only the episode's end says whether the last frame was a success.
        if self._pending is not None:
            self._hold(self._pending, success=False, done=False)
        self._pending = frame

    def end(self, record: TrialRecord) -> EpisodeFiles:
        context = self._require_context("end")
        if self._pending is not None:
            self._hold(self._pending, success=bool(record.success), done=True)
        self._pending = None
        self._drain()
        self._wait()
        self._context = None
        if self._frames == 0:  # an episode that ended before its first step has nothing to store
            return EpisodeFiles()
        episode = int(self.dataset.meta.total_episodes)
        # Saving maps the episode's frames with a progress bar; LeRobot re-enables bars after each load, so again.
        datasets.disable_progress_bars()
        self.dataset.save_episode()
        self._close_episode_files()
        self._append_sidecar(_episode_row(episode, context, record))
        return EpisodeFiles(dataset_episode=episode)

    def discard(self) -> None:
        self._pending, self._buffer, self._buffered_bytes = None, [], 0
        for future in self._futures:
            future.cancel()
        self._wait(raise_errors=False)
        if self.dataset is not None and self.dataset.has_pending_frames():
            self.dataset.clear_episode_buffer()
        self._context = None

    def close(self) -> None:
        if self._context is not None:
            self.discard()
        self._worker.shutdown(wait=True)
        if self.dataset is not None:
            self.dataset.finalize()
            self.dataset = None
        info_path = self.root / "meta" / "info.json"
        if not info_path.exists():
            return
        sidecar = self.root / SIDECAR_DIR
        sidecar.mkdir(parents=True, exist_ok=True)
        for name in RUN_FILES:
            if (self.run_dir / name).exists():
                shutil.copyfile(self.run_dir / name, sidecar / name)
        episodes = json.loads(info_path.read_text(encoding="utf-8"))["total_episodes"]
        info = {"version": SIDECAR_VERSION, "repo_id": self.repo_id, "episodes": episodes}
        (sidecar / "run.json").write_text(json.dumps(info, indent=2) + "\n", encoding="utf-8")

    def _close_episode_files(self) -> None:
        """Write the footers of the episode's data and metadata files now, so a run killed later keeps it. The
        dataset stays open: reopening it would read every episode so far back from disk, for each new one. Its
        chunk settings (`_open`) start the next episode in new files rather than rewriting these."""
        self.dataset.writer.close_writer()
        self.dataset.meta._close_writer()  # LeRobot's public finalize() closes it only once per dataset

    def _require_context(self, method: str) -> TrialContext:
        if self._context is None:
            raise RuntimeError(f"DatasetRecorder.{method}() called outside an episode; call start() first")
        return self._context

    def _hold(self, frame: dict[str, Any], success: bool, done: bool) -> None:
        frame["next.success"] = np.array([success])
        frame["next.done"] = np.array([done])
        self._buffer.append(frame)
        self._frames += 1
        self._buffered_bytes += sum(frame[k].nbytes for k in self._image_keys)
        if self._buffered_bytes > self.max_buffer_bytes:  # a very long episode: hand it over in batches
            self._drain()

    def _drain(self) -> None:
        """Hand the buffered frames, in order, to the worker thread that adds them to the dataset."""
        for frame in self._buffer:
            self._futures.append(self._worker.submit(self.dataset.add_frame, frame))
        self._buffer, self._buffered_bytes = [], 0

    def _wait(self, raise_errors: bool = True) -> None:
        futures, self._futures = self._futures, []
        for future in futures:
            if future.cancelled():
                continue
            error = future.exception()
            if error is not None and raise_errors:
                raise error

    def _open(self, features: dict[str, dict]) -> LeRobotDataset:
        info_path = self.root / "meta" / "info.json"
        if info_path.exists() and json.loads(info_path.read_text(encoding="utf-8")).get("total_episodes", 0) > 0:
            if not any((self.root / "meta" / "episodes").glob("*/*.parquet")):  # else LeRobot would ask the Hub
                raise DatasetError(f"{self.root} is damaged (the run stopped while saving an episode); {RESTORE}")
            dataset = LeRobotDataset.resume(
                self.repo_id, root=self.root, streaming_encoding=self.use_videos, video_backend=video_backend()
            )
            _check_features(self.root, dataset.meta.features, features)
        else:
            if self.root.exists():  # created but no episode saved before the run stopped: start it afresh
                shutil.rmtree(self.root)
            dataset = LeRobotDataset.create(
                self.repo_id,
                fps=self.fps,
                features=features,
                root=self.root,
                robot_type=self.robot_type,
                use_videos=self.use_videos,
                streaming_encoding=self.use_videos,
                video_backend=video_backend(),
            )
        # Any file, however small, is "full": every episode gets its own data, video and metadata files, so a
        # finished episode's files are never reopened and a rollback removes whole files.
        dataset.meta.update_chunk_settings(data_files_size_in_mb=FULL_MB, video_files_size_in_mb=FULL_MB)
        return dataset

    def _append_sidecar(self, row: dict[str, Any]) -> None:
        path = self.root / SIDECAR_DIR / "episodes.jsonl"
        path.parent.mkdir(parents=True, exist_ok=True)
        with path.open("a", encoding="utf-8") as handle:
            handle.write(json.dumps(row, separators=(",", ":")) + "\n")
            handle.flush()
            os.fsync(handle.fileno())


def _check_features(root: Path, stored: dict[str, dict], wanted: dict[str, dict]) -> None:
    def comparable(features: dict[str, dict]) -> dict[str, tuple]:
        return {k: (v["dtype"], tuple(v["shape"]), v.get("names")) for k, v in features.items() if k in wanted}

    if comparable(stored) != comparable(wanted) or not set(wanted) <= set(stored):
        raise DatasetError(
            f"{root} was recorded with other robot features than this run's; "
            "resume with the same robot and cameras, or choose a new --output_dir"
        )


def _episode_row(episode: int, context: TrialContext, record: TrialRecord) -> dict[str, Any]:
    """One sidecar line: which trial the episode is, what it cost and how it scored."""
    instance = context.instance
    return {
        "version": SIDECAR_VERSION,
        "episode_index": episode,
        "trial_index": context.index,
        "instance_id": instance.id,
        "base_id": instance.base_id,
        "perturbation": instance.perturbation,
        "axis": context.axis,
        "staging": context.staging,
        "planned_cost": context.planned_cost,
        "cost": record.cost,
        "cost_unit": context.settings.get("cost_unit"),
        "status": record.status,
        "success": bool(record.success),
        "spl": record.spl,
        "progress": record.progress,
        "path_length": record.path_length,
        "reference_length": record.reference_length,
        "steps": record.steps,
        "settings": dict(context.settings),
        "instance": instance.to_json(),
    }
