"""The run's LeRobotDataset as the page needs it: whether it has videos, and per episode its video files (with the
span of each file the episode takes) and its action and state signals, read from LeRobot's v3 layout."""

from __future__ import annotations

import json
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.compute as pc
import pyarrow.dataset as ds
import pyarrow.parquet as pq

# record.dataset.DATASET_DIR (a test checks they agree): importing that module would load LeRobot and torch, seconds
# the viewer need not spend before it can serve.
DATASET_DIR = "dataset"
# The signals plotted under the videos: the robot's state and the policy's actions, as LeRobot names them.
SIGNALS = ("observation.state", "action")


class Dataset:
    """The dataset in `run_dir/dataset`, read lazily: nothing is opened until a pair is."""

    def __init__(self, run_dir: Path) -> None:
        self.root = Path(run_dir) / DATASET_DIR
        info_path = self.root / "meta" / "info.json"
        self.info: dict[str, Any] = json.loads(info_path.read_text(encoding="utf-8")) if info_path.is_file() else {}

    @property
    def video_keys(self) -> list[str]:
        return [k for k, v in self.info.get("features", {}).items() if v.get("dtype") == "video"]

    def absent_why(self, config: dict[str, Any]) -> str | None:
        """Why the page has no videos of the run with settings `config` (None: it has them)."""
        if not self.info and config.get("record_dataset"):
            return (
                f"this run recorded a dataset, but {self.root} is not there (a hub: run is downloaded without its "
                "episodes), so its videos are absent"
            )
        if not self.info:
            return "this run recorded no dataset (--record_dataset=true records one), so its videos are absent"
        if not self.video_keys:
            return "this run's dataset stores its camera frames as images, not videos, so its videos are absent"
        return None

    @cached_property
    def episodes(self) -> dict[int, dict[str, Any]]:
        """Where each episode's rows and video spans are, from meta/episodes (read once, its columns only)."""
        columns = ["episode_index", "data/chunk_index", "data/file_index", "dataset_from_index", "dataset_to_index"]
        for key in self.video_keys:
            columns += [f"videos/{key}/{c}" for c in ("chunk_index", "file_index", "from_timestamp", "to_timestamp")]
        files = sorted((self.root / "meta" / "episodes").glob("*/*.parquet"))
        if not files:
            return {}
        table = ds.dataset(files, format="parquet").to_table(columns=columns)
        return {row["episode_index"]: row for row in table.to_pylist()}

    def video_files(self) -> list[str]:
        """Every video file of the dataset, relative to its root."""
        return sorted(p.relative_to(self.root).as_posix() for p in (self.root / "videos").glob("**/*.mp4"))

    def episode(self, index: int) -> dict[str, Any] | None:
        """Episode `index`: per camera its video file (relative to the dataset root) and span, and the signals."""
        row = self.episodes.get(index)
        if row is None:  # a run in progress saved it since the index was read
            self.__dict__.pop("episodes", None)
            row = self.episodes.get(index)
        if row is None:
            return None
        videos = []
        for key in self.video_keys:
            chunk, file = row[f"videos/{key}/chunk_index"], row[f"videos/{key}/file_index"]
            path = self.info["video_path"].format(video_key=key, chunk_index=chunk, file_index=file)
            span = [row[f"videos/{key}/from_timestamp"], row[f"videos/{key}/to_timestamp"]]
            videos.append({"key": key, "path": path, "span": span})
        return {"episode": index, "fps": self.info.get("fps"), "videos": videos, "signals": self._signals(row)}

    def _signals(self, row: dict[str, Any]) -> list[dict[str, Any]]:
        path = self.root / self.info["data_path"].format(
            chunk_index=row["data/chunk_index"], file_index=row["data/file_index"]
        )
        features = self.info.get("features", {})
        names = [k for k in SIGNALS if k in features]
        table = pq.read_table(path, columns=["episode_index", "timestamp", *names])
        table = table.filter(pc.equal(table["episode_index"], row["episode_index"]))
        time = [round(float(t), 4) for t in table["timestamp"].to_numpy()]
        out = []
        for name in names:
            values = np.asarray(table[name].to_pylist(), dtype=np.float64).reshape(len(time), -1)
            labels = _labels(features[name].get("names"), name, values.shape[1])
            series = [[round(float(v), 5) for v in values[:, i]] for i in range(values.shape[1])]
            out.append({"name": name, "labels": list(labels), "time": time, "series": series})
        return out


def _labels(names: Any, feature: str, width: int) -> list[str]:
    """A feature's per-dimension names: LeRobot writes a list, or a dict holding one list (e.g. {"motors": [...]})."""
    if isinstance(names, dict) and len(names) == 1:
        names = next(iter(names.values()))
    if isinstance(names, list) and len(names) == width:
        return [str(n) for n in names]
    return [f"{feature}[{i}]" for i in range(width)]
