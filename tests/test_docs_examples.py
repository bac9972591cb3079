"""The README's "Write your own task" example must run as written."""

import re
import runpy
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_the_custom_task_example_runs_and_honours_the_budget(tmp_path, capsys):
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), flags=re.S)
    example = next(b for b in blocks if "class CupTask" in b)
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
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), flags=re.S)
    imports = re.findall(r"^(?:from|import) (lerobot_contrast\S*)", "\n".join(blocks), flags=re.M)
    assert imports and set(imports) == {"lerobot_contrast"}
