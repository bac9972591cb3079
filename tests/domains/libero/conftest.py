"""One LIBERO simulator for the package (building a LIBERO scene takes tens of seconds on a CPU), at 128x128."""

from __future__ import annotations

import pytest

NEEDS = "LIBERO is installed by the test set-up: bash scripts/setup.sh --dev"


@pytest.fixture(scope="package")
def libero_robot():
    pytest.importorskip("libero", reason=NEEDS)
    from lerobot_contrast.domains.libero.config_libero_sim import LiberoSimConfig
    from lerobot_contrast.domains.libero.libero_sim import LiberoSim

    robot = LiberoSim(LiberoSimConfig(observation_width=128, observation_height=128))
    robot.connect()
    yield robot
    robot.disconnect()


@pytest.fixture(scope="package")
def object_task():
    pytest.importorskip("libero", reason=NEEDS)
    from lerobot_contrast.domains.libero.task import LiberoObjectTask

    return LiberoObjectTask(families=["task0"])
