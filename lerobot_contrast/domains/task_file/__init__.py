"""Tasks declared in a YAML task file (format version 1): workspace, objects, instructions, outcome,
perturbations and cost, validated on load with errors that name the file, line and key."""

from lerobot_contrast.domains.task_file.loader import (
    example_names,
    examples_dir,
    load_task_file,
    task_file_path,
    task_from_dict,
)
from lerobot_contrast.domains.task_file.nodes import TaskFileError
from lerobot_contrast.domains.task_file.perturbations import GENERIC
from lerobot_contrast.domains.task_file.schema import VERSION, TaskSpec
from lerobot_contrast.domains.task_file.task import FileTask

__all__ = [
    "GENERIC",
    "VERSION",
    "FileTask",
    "TaskFileError",
    "TaskSpec",
    "example_names",
    "examples_dir",
    "load_task_file",
    "task_file_path",
    "task_from_dict",
]
