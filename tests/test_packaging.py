"""The distributions install under the names LeRobot's plugin discovery looks for, at one version, with a light core,
extras named for what they add, and console scripts beside the `python -m` forms."""

import ast
import importlib.metadata
import subprocess
import sys
from pathlib import Path

import pytest

import lerobot_contrast
from lerobot_contrast import extras
from lerobot_contrast.contrast.errors import UserError

ROOT = Path(__file__).resolve().parents[1]
DISTRIBUTIONS = (
    "lerobot_contrast",
    "navigation_protocol",
    "lerobot_robot_locobot",
    "lerobot_teleoperator_so101_demo",
    "lerobot_policy_language_table",
    "lerobot_policy_tabletop_pointer",
    "lerobot_policy_vln_navigator",
    "lerobot_env_language_table",
)
COMMANDS = ("eval", "report", "review", "view", "publish", "calibrate", "sweep", "twin")
MAINS = {
    "sweep": "lerobot_contrast.sweep.command:main",
    "twin": "lerobot_contrast.twin.__main__:main",
    "view": "lerobot_contrast.view.command:main",
}


def test_every_distribution_is_installed_under_its_underscore_name_at_the_one_version():
    versions = {name: importlib.metadata.version(name) for name in DISTRIBUTIONS}
    assert set(versions.values()) == {lerobot_contrast.__version__}, versions


def test_the_core_leaves_ray_the_training_stack_and_the_test_tools_to_extras():
    core = [r for r in importlib.metadata.requires("lerobot_contrast") if "extra ==" not in r]
    assert "lerobot[dataset,viz]<0.7,>=0.6.1" in core
    assert not [r for r in core if r.startswith(("ray", "jax", "flax", "pytest", "mkdocs", "lerobot[training"))]
    extras = importlib.metadata.metadata("lerobot_contrast").get_all("Provides-Extra")
    assert {"sweep", "train", "libero", "twin", "docs", "dev"} <= set(extras)


def test_each_command_has_a_console_script_in_lerobots_style():
    scripts = {ep.name: ep for ep in importlib.metadata.entry_points(group="console_scripts")}
    for command in COMMANDS:
        script = scripts[f"lerobot-contrast-{command}"]
        assert script.value == MAINS.get(command, f"lerobot_contrast.{command}:main")
        assert callable(script.load()) and (Path(sys.executable).parent / script.name).exists()


def test_a_missing_extra_is_named_with_the_command_that_installs_it(monkeypatch):
    extras.require_extra("sweep", "sweep")  # ray is in this environment (the dev extra)
    monkeypatch.setattr(extras, "find_spec", lambda name: None if name == "ray" else object())
    with pytest.raises(UserError, match=r"^sweep needs the \[sweep\] extra \(ray not installed\): pip install"):
        extras.require_extra("sweep", "sweep")


def test_the_env_plugins_modules_import_one_way():
    """No two modules of the env plugin import each other (DESIGN.md), even inside a function."""
    package = ROOT / "envs/lerobot_env_language_table/lerobot_env_language_table"
    imports = {}
    for path in package.glob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        names = {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom) and node.module}
        imports[path.stem] = {name.rsplit(".", 1)[-1] for name in names if name.startswith(package.name + ".")}
    assert not [(a, b) for a in imports for b in imports[a] if a in imports.get(b, ())]


def test_lerobot_plugin_discovery_imports_both_plugins():
    code = (
        "import sys\n"
        "from lerobot.utils.import_utils import register_third_party_plugins\n"
        "register_third_party_plugins()\n"
        "print('lerobot_robot_locobot' in sys.modules, 'lerobot_policy_language_table' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["True", "True"]


def test_the_evaluator_and_the_locobot_plugin_both_depend_on_the_navigation_protocol_only():
    """Neither distribution requires the other for VLN: what they share is the small navigation_protocol."""
    for name in ("lerobot_contrast", "lerobot_robot_locobot"):
        assert "navigation_protocol<0.3,>=0.2.0" in importlib.metadata.requires(name)
    assert importlib.metadata.requires("navigation_protocol") is None
    assert "lerobot_contrast" not in " ".join(importlib.metadata.requires("lerobot_robot_locobot"))


def _pyprojects() -> dict[str, tuple[Path, set[str]]]:
    """Each of this repository's distributions: its folder and the repository's distributions it requires (extras
    included), read from every pyproject.toml."""
    import re
    import tomllib

    found = {}
    for path in ROOT.rglob("pyproject.toml"):
        if ".venv" in path.parts:
            continue
        project = tomllib.loads(path.read_text(encoding="utf-8"))["project"]
        requires = list(project.get("dependencies", []))
        requires += [r for group in project.get("optional-dependencies", {}).values() for r in group]
        names = {re.match(r"[A-Za-z0-9_.-]+", r).group(0).replace("-", "_").lower() for r in requires}
        found[project["name"]] = (path.parent, names)
    return {name: (folder, needs & set(found) - {name}) for name, (folder, needs) in found.items()}


def _needs_all(name: str, graph: dict[str, set[str]]) -> set[str]:
    seen, todo = set(), [name]
    while todo:
        for need in graph[todo.pop()] - seen:
            seen.add(need)
            todo.append(need)
    return seen


def test_no_two_distributions_require_each_other_directly_or_through_others():
    graph = {name: needs for name, (_, needs) in _pyprojects().items()}
    assert set(graph) == set(DISTRIBUTIONS)
    circles = sorted(name for name in graph if name in _needs_all(name, graph))
    assert not circles, f"distributions in a circle of requirements: {circles}"


def test_no_module_names_a_module_of_a_distribution_its_own_does_not_require():
    """Imports, and "module:function" strings (registries, entry points), of each distribution's own package."""
    import re

    projects = _pyprojects()
    graph = {name: needs for name, (_, needs) in projects.items()}
    named = re.compile(r"^([a-z0-9_]+)(?:\.[a-z0-9_]+)*:[a-z0-9_]+$")
    wrong = []
    for name, (folder, _) in projects.items():
        allowed = _needs_all(name, graph) | {name}
        for path in (folder / name).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if isinstance(node, ast.Import):
                    tops = [alias.name.split(".")[0] for alias in node.names]
                elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                    tops = [node.module.split(".")[0]]
                elif isinstance(node, ast.Constant) and isinstance(node.value, str) and named.match(node.value):
                    tops = [node.value.split(".")[0].split(":")[0]]
                else:
                    continue
                wrong += [
                    f"{path.relative_to(ROOT)} names {top}" for top in tops if top in graph and top not in allowed
                ]
    assert not wrong, wrong
