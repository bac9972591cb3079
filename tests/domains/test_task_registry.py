"""Tasks are found by name through the `lerobot_contrast.tasks` entry points, so a package adds one without
editing this one; shipped task files and task-file paths load by the same call."""

import pytest

from lerobot_contrast import Task, UserError, load_task, task_names
from tests.contrast.toy_task import ToyTask


def test_the_built_in_domains_are_registered():
    assert {"language_table", "vln"} <= set(task_names())
    assert all(isinstance(load_task(name), Task) for name in ("language_table", "vln", "so101_blocks"))


def test_an_installed_package_registers_its_task_by_entry_point(tmp_path, monkeypatch):
    dist = tmp_path / "toy_tasks-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: toy_tasks\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text("[lerobot_contrast.tasks]\ntoy = tests.contrast.toy_task:ToyTask\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert "toy" in task_names()
    assert isinstance(load_task("toy"), ToyTask)


def test_an_unknown_task_names_the_choices():
    with pytest.raises(UserError, match=r"--task: unknown task 'nope'; choose from: language_table, .*so101_blocks"):
        load_task("nope")
