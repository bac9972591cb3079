"""The plugin distributions are installed under the names LeRobot's plugin discovery looks for."""

import importlib.metadata
import subprocess
import sys


def test_the_three_distributions_are_installed_with_underscore_names():
    names = {d.metadata["Name"] for d in importlib.metadata.distributions()}
    assert {"lerobot_contrast", "lerobot_robot_locobot", "lerobot_policy_language_table"} <= names
    assert "lerobot[dataset,training,viz]<0.7,>=0.6.1" in importlib.metadata.requires("lerobot_contrast")


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
        assert "navigation_protocol" in importlib.metadata.requires(name)
    assert importlib.metadata.requires("navigation_protocol") is None
    assert "lerobot_contrast" not in " ".join(importlib.metadata.requires("lerobot_robot_locobot"))
