"""`view --bundle=DIR`: the page as a static site (HTML, JavaScript, the runs' data as scripts, the videos) that
opens from disk in a browser, with no Python and no server; written whole or not at all."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.view.episodes import Dataset
from lerobot_contrast.view.payload import Inputs, build
from lerobot_contrast.view.static_files import script, static_files


class BundleError(UserError):
    pass


def write_bundle(inputs: Inputs, out: Path, video_base: str | None = None) -> list[Path]:
    """Write the page for `inputs` into `out` (replacing a bundle there); returns the files written. With
    `video_base` (one run), the page takes the dataset's videos from there instead of copies in the bundle: a
    published run's `view/` reads `../dataset/`."""
    out = Path(out)
    if out.exists() and any(out.iterdir()) and not (out / "index.html").is_file():
        raise BundleError(f"--bundle={out}: a folder that holds other files; choose a new or empty folder")
    tmp = out.with_name(out.name + ".tmp")
    shutil.rmtree(tmp, ignore_errors=True)
    try:
        _write(inputs, tmp, video_base)
        if out.exists():
            shutil.rmtree(out)
        os.replace(tmp, out)
    except OSError as error:
        shutil.rmtree(tmp, ignore_errors=True)
        raise BundleError(
            f"--bundle={out}: cannot write the bundle ({error.strerror}); choose a writable folder"
        ) from None
    return sorted(p for p in out.rglob("*") if p.is_file())


def _write(inputs: Inputs, root: Path, video_base: str | None) -> None:
    (root / "static").mkdir(parents=True)
    for path in static_files():
        shutil.copyfile(path, (root if path.name == "index.html" else root / "static") / path.name)
    doc = build(inputs, live=False)
    paths = {f"r{k}": run.path for k, run in enumerate(inputs.runs)}
    for run in doc["runs"]:
        if video_base is not None:
            run["video_base"] = video_base
        if run["videos_absent"] is None:
            _episodes(Dataset(paths[run["id"]]), run, root, copy_videos=video_base is None)
    (root / "data").mkdir(exist_ok=True)  # a run that recorded no dataset has no episodes to make it
    (root / "data" / "runs.js").write_text(script("viewData", doc), encoding="utf-8")


def _episodes(dataset: Dataset, run: dict, root: Path, copy_videos: bool) -> None:
    """Each recorded trial's episode as a script, and (unless the page reads them elsewhere) its video files."""
    folder = root / "data" / "episodes" / run["id"]
    folder.mkdir(parents=True)
    videos: set[str] = set()
    for trial in run["trials"]:
        if trial["episode"] is None or (episode := dataset.episode(trial["episode"])) is None:
            continue
        (folder / f"{trial['episode']}.js").write_text(
            script("viewEpisode", {"run": run["id"], **episode}), encoding="utf-8"
        )
        videos.update(v["path"] for v in episode["videos"])
    for relative in sorted(videos) if copy_videos else []:
        target = root / "videos" / run["id"] / relative
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(dataset.root / relative, target)
