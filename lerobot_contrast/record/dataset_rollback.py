"""Bring a run's LeRobotDataset back to the episodes its journal names. A run killed after saving an episode (or
part of one) but before journaling its trial leaves that episode behind; the resumed run records it again.

The recorder gives each episode its own data, video and metadata files: rolling back removes files and rewrites
the counts, it never cuts a file. An episode the journal names whose files are missing or damaged is refused."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path
from typing import Any

import av
import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
from lerobot.datasets.compute_stats import aggregate_stats
from lerobot.datasets.io_utils import load_info, load_tasks, write_info, write_stats, write_tasks
from lerobot.datasets.utils import DEFAULT_EPISODES_PATH
from lerobot.utils.utils import unflatten_dict

from lerobot_contrast.contrast.errors import UserError

EPISODE_FOLDERS = ("data", "videos", "meta/episodes")
SIDECAR_EPISODES = "meta/contrast_eval/episodes.jsonl"
# A dataset that lacks what the journal names cannot be resumed into: its episodes would no longer be the trials'.
RESTORE = (
    "restore it from a copy and resume, or run the evaluation again into a new --output_dir "
    "(the journal and the Rerun files are intact)"
)


class DatasetError(UserError):
    pass


def roll_back(root: Path, keep: int) -> None:
    """Keep the first `keep` episodes of the dataset at `root`; remove every file of a later or unfinished one.
    A kept episode with a file missing or damaged is refused in one line naming the file, and nothing changes."""
    if keep == 0:
        if root.exists():
            shutil.rmtree(root)
        return
    if not root.is_dir():
        raise DatasetError(f"{root} is missing, but the journal names {keep} episodes of it; {RESTORE}")
    rows = _kept_rows(root, keep)
    try:
        info = load_info(root)
    except (OSError, ValueError, KeyError, TypeError):
        raise DatasetError(f"{root}: meta/info.json is missing or damaged; {RESTORE}") from None
    videos = [k for k, v in info.features.items() if v["dtype"] == "video"]
    _check_episode_files(root, info.data_path, info.video_path, videos, rows)
    wanted = {_relative(DEFAULT_EPISODES_PATH, row, "meta/episodes") for row in rows}
    wanted |= {_relative(info.data_path, row, "data") for row in rows}
    for key in videos:
        wanted |= {_relative(info.video_path, row, f"videos/{key}", video_key=key) for row in rows}
    stray = [
        path
        for folder in EPISODE_FOLDERS
        for path in sorted((root / folder).rglob("*"))
        if path.is_file() and path.relative_to(root).as_posix() not in wanted
    ]
    for path in stray:
        path.unlink()
    shutil.rmtree(root / "images", ignore_errors=True)  # LeRobot's staging of an episode being saved
    if stray or info.total_episodes != keep:
        _rewrite_totals(root, rows)
    _trim_sidecar(root / SIDECAR_EPISODES, keep)


def _kept_rows(root: Path, keep: int) -> list[dict[str, Any]]:
    """The metadata rows of episodes 0 .. keep-1, or an error naming how many the dataset really holds."""
    rows: dict[int, dict[str, Any]] = {}
    unreadable = []
    for path in sorted((root / "meta" / "episodes").glob("*/*.parquet")):
        try:
            table = pq.read_table(path)
        except (OSError, pa.ArrowException):  # written when a kill struck: an episode the journal never named
            unreadable.append(path)
            continue
        rows.update((row["episode_index"], row) for row in table.to_pylist() if row["episode_index"] < keep)
    if sorted(rows) != list(range(keep)):
        held = f"{root} holds {len(rows)} complete episodes of the first {keep} that the journal names"
        if unreadable:  # most likely the file that held the missing ones
            raise DatasetError(f"{unreadable[0]} is damaged, and {held}; {RESTORE}")
        raise DatasetError(f"{held}; {RESTORE}")
    return [rows[index] for index in range(keep)]


def _check_episode_files(
    root: Path, data_path: str, video_path: str, videos: list[str], rows: list[dict[str, Any]]
) -> None:
    """Every kept episode's frames in its data file, and its video files there and readable; else one line
    naming the first file that is not."""
    frames: dict[Path, set[int] | None] = {}
    for row in rows:
        path = root / _relative(data_path, row, "data")
        if path not in frames:
            frames[path] = _frame_indexes(path)
        held = frames[path]
        if held is None or not set(range(row["dataset_from_index"], row["dataset_to_index"])) <= held:
            _refuse(path, row)
        for key in videos:
            video = root / _relative(video_path, row, f"videos/{key}", video_key=key)
            if not _readable_video(video, row[f"videos/{key}/to_timestamp"]):
                _refuse(video, row)


def _frame_indexes(path: Path) -> set[int] | None:
    """The global frame indexes a data file holds; None when it is missing or cannot be read."""
    try:
        return set(pq.read_table(path, columns=["index"]).column("index").to_pylist())
    except (OSError, pa.ArrowException):
        return None


def _readable_video(path: Path, until_s: float) -> bool:
    """Whether the video opens and lasts as long as the episodes it holds (within a frame or so)."""
    try:
        with av.open(str(path)) as container:
            stream = container.streams.video[0]
            duration = stream.duration * stream.time_base if stream.duration else container.duration / av.time_base
            return float(duration) >= until_s - 2 / float(stream.average_rate or 1)
    except (OSError, av.error.FFmpegError, IndexError, TypeError):
        return False


def _refuse(path: Path, row: dict[str, Any]) -> None:
    state = "is missing" if not path.exists() else "is damaged"
    raise DatasetError(f"{path} {state} (it holds episode {row['episode_index']}, which the journal names); {RESTORE}")


def _relative(pattern: str, row: dict[str, Any], prefix: str, **names: str) -> str:
    chunk, file = row[f"{prefix}/chunk_index"], row[f"{prefix}/file_index"]
    return pattern.format(chunk_index=chunk, file_index=file, **names)


def _rewrite_totals(root: Path, rows: list[dict[str, Any]]) -> None:
    """info.json, stats.json and tasks.parquet as LeRobot left them after saving the last kept episode."""
    used = {task for row in rows for task in row["tasks"]}
    tasks = load_tasks(root)
    tasks = tasks[tasks.index.isin(used)]  # tasks are appended in first use order: these are a prefix
    write_tasks(tasks, root)
    episode_stats = [_episode_stats(row) for row in rows]
    stats = episode_stats[0]
    for episode in episode_stats[1:]:  # episode by episode, as LeRobot aggregates while recording
        stats = aggregate_stats([stats, episode])
    write_stats(stats, root)
    info = load_info(root)
    info.total_episodes = len(rows)
    info.total_frames = int(rows[-1]["dataset_to_index"])
    info.total_tasks = len(tasks)
    info.splits = {"train": f"0:{len(rows)}"}
    write_info(info, root)


def _episode_stats(row: dict[str, Any]) -> dict[str, dict[str, np.ndarray]]:
    flat = {key.removeprefix("stats/"): np.asarray(value) for key, value in row.items() if key.startswith("stats/")}
    return unflatten_dict(flat)


def _trim_sidecar(path: Path, keep: int) -> None:
    """Drop the sidecar lines of removed episodes, and a line a kill cut off."""
    if not path.exists():
        return
    lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
    kept = [line for line in lines if (episode := _sidecar_episode(line)) is not None and episode < keep]
    if kept != lines:
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_text("".join(kept), encoding="utf-8")
        os.replace(tmp, path)


def _sidecar_episode(line: str) -> int | None:
    """The episode a complete sidecar line describes; None for a line a kill cut off."""
    try:
        return int(json.loads(line)["episode_index"]) if line.endswith("\n") else None
    except (ValueError, KeyError, TypeError):
        return None
