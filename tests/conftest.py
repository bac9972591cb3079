"""Fixtures shared across the suite."""

import os
import signal

import datasets
import pytest
from huggingface_hub import HfFileSystem, constants

from tests.fake_hub import FakeHub

# MuJoCo fixes its GL backend when first imported, and LeRobot's plugin discovery imports it (lerobot_env_so101) in
# whichever test first asks for plugins: offscreen EGL for the whole session, as the twin's camera needs.
os.environ.setdefault("MUJOCO_GL", "egl")

# Ctrl-C is part of what the suite checks. A shell starts background jobs with SIGINT ignored, which Python and the
# evaluations it spawns would keep; restore Python's own handler so the suite behaves the same however it is started.
signal.signal(signal.SIGINT, signal.default_int_handler)


# The test files that start a local Ray: on one worker, so that two Ray clusters never start at once.
RAY_FILES = {"test_sweep.py", "test_sweep_cluster.py", "test_sweep_ray_nodes.py"}


@pytest.hookimpl(tryfirst=True)  # before xdist's own hook reads the groups
def pytest_collection_modifyitems(config, items):
    """With workers (`-n`, as .ci/run runs the suite), the Ray files' tests share one worker; the other tests go
    wherever a worker is free (a module fixture then runs once per worker that needs it)."""
    if config.getoption("dist", "no") == "no":
        return
    for item in items:
        if item.path.name in RAY_FILES:
            item.add_marker(pytest.mark.xdist_group("ray"))


@pytest.fixture(autouse=True)
def wall_clock_after():
    """The robot's clock is chosen once per process (clock/robot_clock.py): a test that put a twin's simulated clock
    there gives the next test on its worker the wall clock back, not a clock whose twin has stopped."""
    yield
    from lerobot_contrast.clock.robot_clock import use_clock

    use_clock("wall")


@pytest.fixture
def hub(monkeypatch, tmp_path):
    """A fresh fake Hub, with every client setting pointed at it; nothing can reach the internet."""
    fake = FakeHub()
    endpoint = fake.start()
    monkeypatch.setenv("HF_TOKEN", fake.token)
    monkeypatch.setenv("HF_ENDPOINT", endpoint)
    monkeypatch.setenv("HF_HUB_DISABLE_XET", "1")
    monkeypatch.setenv("HF_HOME", str(tmp_path / "hf_home"))
    monkeypatch.setattr(constants, "ENDPOINT", endpoint)
    monkeypatch.setattr(constants, "HUGGINGFACE_CO_URL_TEMPLATE", endpoint + "/{repo_id}/resolve/{revision}/{filename}")
    monkeypatch.setattr(constants, "HF_HUB_DISABLE_XET", True)
    monkeypatch.setattr(constants, "HF_HUB_CACHE", str(tmp_path / "hub_cache"))
    monkeypatch.setattr(datasets.config, "HF_ENDPOINT", endpoint)
    monkeypatch.setattr(datasets.config, "HUB_DATASETS_URL", endpoint + "/datasets/{repo_id}/resolve/{revision}/{path}")
    HfFileSystem.clear_instance_cache()
    yield fake
    fake.stop()
    HfFileSystem.clear_instance_cache()
