"""The scripts under scripts/ (bench/, study/, train/, figures/), found by name and loaded as modules so tests call
their analysis directly."""

import importlib.util
from pathlib import Path
from types import ModuleType

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"


def script_path(name: str) -> Path:
    """scripts/*/NAME.py."""
    found = sorted(SCRIPTS.glob(f"*/{name}.py"))
    if len(found) != 1:
        raise FileNotFoundError(f"no single scripts/*/{name}.py: {found}")
    return found[0]


def load_script(name: str) -> ModuleType:
    """scripts/*/NAME.py as a module."""
    spec = importlib.util.spec_from_file_location(name, script_path(name))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
