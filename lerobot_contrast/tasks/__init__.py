"""Task domains by name: each provides instances, perturbations, grounding and success judgement."""

from __future__ import annotations

from importlib import import_module
from typing import Any

from lerobot_contrast.contrast.errors import UserError

TASKS = {
    "language_table": ("lerobot_contrast.tasks.language_table", "LanguageTableTask"),
    "vln": ("lerobot_contrast.tasks.vln", "VLNTask"),
}

# The gymnasium id of the simulator each task runs in.
SIM_IDS = {
    "language_table": "lerobot_contrast/LanguageTable-v0",
}


def make_task(name: str, **kwargs: Any) -> Any:
    try:
        module, attr = TASKS[name]
    except KeyError:
        raise UserError(f"--task: unknown task {name!r}; choose from: {', '.join(TASKS)}") from None
    return getattr(import_module(module), attr)(**kwargs)
