"""The Python examples of the README and the documentation run as written, through the public API only."""

import runpy

from tests.docs_pages import ROOT, code_blocks

TASKS_PAGE = ROOT / "docs" / "tasks.md"


def test_the_custom_task_example_runs_and_honours_the_budget(tmp_path, capsys):
    example = next(b for b in code_blocks("python", [TASKS_PAGE]) if "class CupTask" in b)
    script = tmp_path / "example.py"
    script.write_text(example, encoding="utf-8")
    runpy.run_path(str(script), run_name="__main__")
    out = capsys.readouterr().out
    rows = [line.split() for line in out.strip().splitlines()]
    assert rows[0][:3] == ["0", "original", "done"]
    assert any(row[1] == "LB" for row in rows) and any(row[1] == "S" for row in rows)
    cumulative = [float(row[-1]) for row in rows]
    assert cumulative[-1] > 2.0 and all(c <= 2.0 for c in cumulative[:-1])


def test_the_python_examples_use_only_the_public_api():
    imports = [
        line.split()[1]
        for block in code_blocks("python")
        for line in block.splitlines()
        if line.startswith(("from lerobot_contrast", "import lerobot_contrast"))
    ]
    assert imports and set(imports) == {"lerobot_contrast"}
