"""Data flows one way: no two modules import each other, directly or through others (lazy and type-only imports
count too), and no folder of modules imports back a folder that imports it."""

import ast
from pathlib import Path

import numpy as np
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = [
    ROOT / "lerobot_contrast",
    ROOT / "robots" / "lerobot_robot_locobot" / "lerobot_robot_locobot",
    ROOT / "protocols" / "navigation_protocol" / "navigation_protocol",
]


def _modules() -> dict[str, Path]:
    modules = {}
    for root in PACKAGES:
        for path in root.rglob("*.py"):
            parts = path.relative_to(root.parent).with_suffix("").parts
            modules[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return modules


def _imported(module: str, path: Path) -> set[str]:
    """Every module name `module` imports anywhere in its file, relative imports resolved."""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                base = f"{anchor}.{base}" if base else anchor
            names |= {base} | {f"{base}.{alias.name}" for alias in node.names}
    return names


def import_graph() -> set[tuple[str, str]]:
    """An edge (a, b) for each module a of this repository's packages that imports module b of them."""
    modules = _modules()
    edges = set()
    for module, path in modules.items():
        for name in _imported(module, path):
            while name and name not in modules:  # `from pkg import name` where name is not a module
                name = name.rpartition(".")[0]
            if name and name != module and not module.startswith(name + "."):  # a package's own parents run first
                edges.add((module, name))
    return edges


def _cycles(edges: set[tuple[str, str]]) -> list[list[str]]:
    """The strongly connected components with more than one member: each a set of nodes importing each other."""
    nodes = sorted({n for edge in edges for n in edge})
    index = {n: k for k, n in enumerate(nodes)}
    rows, cols = zip(*[(index[a], index[b]) for a, b in edges], strict=True) if edges else ((), ())
    matrix = coo_array((np.ones(len(rows)), (rows, cols)), shape=(len(nodes), len(nodes)))
    _, labels = connected_components(matrix, directed=True, connection="strong")
    groups = [[n for n, label in zip(nodes, labels, strict=True) if label == k] for k in set(labels)]
    return sorted(group for group in groups if len(group) > 1)


def test_no_module_imports_itself_back():
    assert _cycles(import_graph()) == []


def test_no_folder_imports_itself_back():
    modules = _modules()
    folders = {(modules[a].parent, modules[b].parent) for a, b in import_graph()}
    named = {(str(a.relative_to(ROOT)), str(b.relative_to(ROOT))) for a, b in folders if a != b}
    assert _cycles(named) == []


def _crossing(source: str, target: str) -> list[tuple[str, str]]:
    return [(a, b) for a, b in import_graph() if a.startswith(source) and b.startswith(target)]


def test_the_locobot_plugin_imports_nothing_from_the_evaluator():
    """The host finds its simulated apartment by entry point, and scenes cross to the evaluator as JSON."""
    assert _crossing("lerobot_robot_locobot", "lerobot_contrast") == []


def test_the_evaluator_imports_nothing_from_the_locobot_plugin():
    """VLN in simulation runs on the in-process vln_sim robot; both sides share only navigation_protocol."""
    assert _crossing("lerobot_contrast", "lerobot_robot_locobot") == []
    assert _crossing("navigation_protocol", "lerobot_") == []
    assert _crossing("lerobot_contrast", "navigation_protocol") != []
    assert _crossing("lerobot_robot_locobot", "navigation_protocol") != []
