"""Task domains by name: each provides instances, perturbations, grounding and success judgement."""

from __future__ import annotations

from importlib import import_module
from typing import Any

from lerobot_contrast.contrast.errors import UserError

TASKS = {
    "language_table": ("lerobot_contrast.tasks.language_table", "LanguageTableTask"),
    "vln": ("lerobot_contrast.tasks.vln", "VLNTask"),
}


def make_task(name: str, **kwargs: Any) -> Any:
    """A task by name (a built-in domain or a shipped example task file) or by the path of a task file."""
    if name in TASKS:
        module, attr = TASKS[name]
        return getattr(import_module(module), attr)(**kwargs)
    from lerobot_contrast.tasks.task_file import example_names, load_task, task_file_path

    if task_file_path(name) is None:
        choices = ", ".join([*TASKS, *example_names()])
        raise UserError(f"--task: unknown task {name!r}; choose from: {choices}, or give the path of a task .yaml file")
    return load_task(name, **kwargs)
