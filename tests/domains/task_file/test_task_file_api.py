"""The documentation's "Write your own task" example (a task file and the Python API in a few lines) runs as written."""

from __future__ import annotations

import re
import runpy
from pathlib import Path

TASKS_PAGE = Path(__file__).resolve().parents[3] / "docs" / "tasks.md"
BLOCKS = re.findall(r"```(yaml|python)\n(.*?)```", TASKS_PAGE.read_text(encoding="utf-8"), flags=re.S)
MY_TABLE = next(code for kind, code in BLOCKS if kind == "yaml" and "name: my_table" in code)
EXAMPLE = next(code for kind, code in BLOCKS if kind == "python" and 'load_task("my_table.yaml")' in code)


def test_the_task_file_example_loads_perturbs_plans_evaluates_and_reports(tmp_path, monkeypatch, capsys):
    (tmp_path / "my_table.yaml").write_text(MY_TABLE, encoding="utf-8")
    (tmp_path / "example.py").write_text(EXAMPLE, encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    runpy.run_path("example.py", run_name="__main__")
    first, *table = capsys.readouterr().out.strip().splitlines()
    before, after = first.split(" -> ")
    assert before != after and before.replace("shelf", "tray") == after.replace("shelf", "tray")
    rows = {line.split()[0]: line.split() for line in table[2:] if not line.startswith("-")}
    assert set(rows) == {"original", "ΔL", "ΔLB", "ΔS", "ΔSB", "all"}
    assert float(rows["ΔL"][-1]) == float(rows["ΔLB"][-1]) == 0.0  # wording costs nothing to stage
    assert float(rows["all"][-1]) > 3.0 and float(rows["ΔS"][-1]) > 0.0  # stops just past the 3 m budget
