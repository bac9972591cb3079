"""The README's "Write your own task" example must run as written."""

import re
import subprocess
import sys
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_the_custom_task_example_runs_and_honours_the_budget(tmp_path):
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), flags=re.S)
    example = next(b for b in blocks if "class CupTask" in b)
    script = tmp_path / "example.py"
    script.write_text(example, encoding="utf-8")
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, check=True).stdout
    rows = [line.split() for line in out.strip().splitlines()]
    assert rows[0][:3] == ["0", "original", "done"]
    assert any(row[1] == "LB" for row in rows) and any(row[1] == "S" for row in rows)
    cumulative = [float(row[-1]) for row in rows]
    assert cumulative[-1] > 2.0 and all(c <= 2.0 for c in cumulative[:-1])
