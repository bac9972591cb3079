"""Tasks by name: the domains registered under the `lerobot_contrast.tasks` entry point group (ours and any
installed package's), the shipped example task files, and task files by path."""

from __future__ import annotations

from importlib.metadata import entry_points
from typing import Any

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.task import Task

TASK_GROUP = "lerobot_contrast.tasks"


def task_names() -> list[str]:
    """The registered task domains, e.g. language_table and vln."""
    return sorted(entry.name for entry in entry_points(group=TASK_GROUP))


def load_task(name: str, **kwargs: Any) -> Task:
    """A task by name (a registered domain or a shipped example task file) or by the path of a task file.

    A package adds a domain with an entry point, e.g. in its pyproject.toml:
    `[project.entry-points."lerobot_contrast.tasks"] my_task = "my_package.task:MyTask"`.
    """
    registered = entry_points(group=TASK_GROUP, name=name)
    if registered:
        return next(iter(registered)).load()(**kwargs)
    from lerobot_contrast.domains.task_file import example_names, load_task_file, task_file_path

    if task_file_path(name) is None:
        choices = ", ".join([*task_names(), *example_names()])
        raise UserError(f"--task: unknown task {name!r}; choose from: {choices}, or give the path of a task .yaml file")
    return load_task_file(name, **kwargs)
