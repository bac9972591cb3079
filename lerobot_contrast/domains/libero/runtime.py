"""Loading LIBERO without questions: MuJoCo's renderer (EGL unless MUJOCO_GL says otherwise), LIBERO's config file
(so its first import never calls input()), the checked assets; every failure as one line that names the fix."""

from __future__ import annotations

import importlib.util
import os
from functools import cache
from pathlib import Path
from typing import Any

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.domains.libero import assets

INSTALL = "pip install 'lerobot_contrast[libero]' (in this repository: bash scripts/setup.sh --dev)"
CONFIG_DIR = Path("~/.cache/lerobot_contrast/libero").expanduser()


class LiberoMissingError(UserError):
    pass


class RenderBackendError(UserError):
    pass


def _package_dir() -> Path:
    spec = importlib.util.find_spec("libero")
    if spec is None or not spec.submodule_search_locations:
        raise LiberoMissingError(f"LIBERO is not installed; install it with: {INSTALL}")
    return Path(next(iter(spec.submodule_search_locations))) / "libero"


def write_config(benchmark_root: Path, assets_dir: Path | None) -> Path:
    """A LIBERO config.yaml in our own folder, pointing at the installed package (and the checked assets)."""
    CONFIG_DIR.mkdir(parents=True, exist_ok=True)
    paths = {
        "benchmark_root": benchmark_root,
        "bddl_files": benchmark_root / "bddl_files",
        "init_states": benchmark_root / "init_files",
        "datasets": CONFIG_DIR / "datasets",
        "assets": assets_dir or benchmark_root / "assets",
    }
    text = "".join(f"{key}: {value}\n" for key, value in paths.items())
    path = CONFIG_DIR / "config.yaml"
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.write_text(text, encoding="utf-8")
    return CONFIG_DIR


@cache
def load() -> Any:
    """`libero.libero`, configured; raises one-line UserErrors for a missing LIBERO, renderer or asset."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    if os.environ["MUJOCO_GL"] in ("egl", "osmesa"):
        os.environ.setdefault("PYOPENGL_PLATFORM", os.environ["MUJOCO_GL"])
    root = _package_dir()
    assets_dir = assets.locate(full=False)
    if "LIBERO_CONFIG_PATH" not in os.environ and not Path("~/.libero/config.yaml").expanduser().exists():
        os.environ["LIBERO_CONFIG_PATH"] = str(write_config(root, assets_dir))
    try:
        import libero.libero as libero
    except (ImportError, OSError, EOFError) as error:
        raise LiberoMissingError(
            f"LIBERO cannot be imported ({' '.join(str(error).split())[:160]}); {INSTALL}"
        ) from None
    if assets_dir is not None:
        libero._assets_path_cache = str(assets_dir)  # what get_assets_path() returns before any Hub download
    check_renderer()
    return libero


def check_renderer() -> None:
    """Open a tiny offscreen context with the MUJOCO_GL backend, so a missing one is named before LIBERO starts."""
    backend = os.environ.get("MUJOCO_GL", "egl")
    try:
        import mujoco

        context = mujoco.GLContext(16, 16)
        context.make_current()
        context.free()
    except Exception as error:
        raise RenderBackendError(
            f"no rendering backend: MUJOCO_GL={backend} does not load ({' '.join(str(error).split())[:120]}); "
            "install Mesa's EGL (apt-get install libegl1 libgl1-mesa-dri) or run with MUJOCO_GL=osmesa after "
            "apt-get install libosmesa6"
        ) from None
