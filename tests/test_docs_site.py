"""The documentation site builds without a warning (broken links and references fail), and its API reference
documents exactly the public API."""

import importlib
import re
import subprocess
import sys

import lerobot_contrast
from tests.docs_pages import ROOT, text


def test_mkdocs_builds_the_site_strictly(tmp_path):
    mkdocs = [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")]
    built = subprocess.run(mkdocs, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert built.returncode == 0, built.stderr[-3000:]
    api = (tmp_path / "site" / "api" / "index.html").read_text(encoding="utf-8")
    assert 'id="lerobot_contrast.spine.evaluation.run"' in api  # rendered from the docstrings, not left as `:::`


def test_the_api_reference_covers_every_public_name_and_nothing_else():
    documented = re.findall(r"^::: ([\w.]+)$", text(ROOT / "docs" / "api.md"), flags=re.M)
    names = {path.rsplit(".", 1)[-1] for path in documented}
    assert names == set(lerobot_contrast.__all__)
    for path in documented:  # each entry documents the very object the public name gives
        module, name = path.rsplit(".", 1)
        try:
            documented_object = importlib.import_module(path)
        except ModuleNotFoundError:
            documented_object = getattr(importlib.import_module(module), name)
        assert documented_object is getattr(lerobot_contrast, name), path
