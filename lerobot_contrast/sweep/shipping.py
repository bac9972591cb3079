"""This project's code, as Ray's runtime environment ships it to a cluster's nodes: each of its packages and its
distribution's metadata (entry points, LeRobot's plugin discovery) as `py_modules`, from a checkout or an install."""

from __future__ import annotations

import importlib.metadata
import importlib.util
from pathlib import Path
from typing import Any

# The project's distributions a cell may import: the contrast sets and the sibling plugins its tasks use.
DISTRIBUTIONS = (
    "lerobot-contrast",
    "navigation-protocol",
    "lerobot-robot-locobot",
    "lerobot-policy-language-table",
    "lerobot-policy-tabletop-pointer",
    "lerobot-env-language-table",
    "lerobot-policy-vln-navigator",
)
EXCLUDES = ["__pycache__", "*.pyc"]
# Each cell runs on one thread: the cells are the parallelism. Set when the worker process starts, before its
# numerical libraries read them (Ray would otherwise pass on the driver's OMP_NUM_THREADS).
ONE_THREAD = {name: "1" for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}


def shipped_paths() -> list[Path]:
    """Each installed distribution's package folder and metadata folder (`*.dist-info`): a node puts each on its
    path, so `import` finds the package and importlib.metadata its entry points, as in this environment."""
    paths = []
    for name in DISTRIBUTIONS:
        spec = importlib.util.find_spec(name.replace("-", "_"))
        metadata = _metadata_folder(name)
        if spec is None or not spec.submodule_search_locations or metadata is None:
            continue  # not installed here, so no cell of this machine's sweeps uses it
        paths += [Path(next(iter(spec.submodule_search_locations))), metadata]
    return paths


def _metadata_folder(name: str) -> Path | None:
    """The installed distribution's `*.dist-info`, before an `*.egg-info` a build left in a checkout (found first
    when the sweep starts there, and possibly stale)."""
    found = [Path(dist._path) for dist in importlib.metadata.distributions(name=name) if hasattr(dist, "_path")]
    return next((path for path in found if path.suffix == ".dist-info"), found[0] if found else None)


def runtime_env() -> dict[str, Any]:
    """The runtime environment of a sweep on a cluster: this project's code shipped, one thread per cell."""
    return {"py_modules": [str(path) for path in shipped_paths()], "excludes": EXCLUDES, "env_vars": ONE_THREAD}
