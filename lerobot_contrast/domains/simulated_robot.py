"""What every in-process simulator shares as a LeRobot `Robot`: nothing to calibrate or configure, connecting builds
its world and disconnecting drops it."""

from __future__ import annotations

from abc import abstractmethod
from typing import Any

from lerobot.robots import Robot
from lerobot.utils.errors import DeviceAlreadyConnectedError, DeviceNotConnectedError


class SimulatedRobot(Robot):
    simulated = True  # the evaluator may step it as fast as it computes

    def __init__(self, config: Any) -> None:
        super().__init__(config)
        self.config = config
        self.cameras: dict[str, Any] = {}  # rendered cameras, not LeRobot camera devices
        self._world: Any = None

    @abstractmethod
    def _build(self) -> Any:
        """A fresh world (physics, apartment), as the robot finds it when it connects."""

    @property
    def is_connected(self) -> bool:
        return self._world is not None

    @property
    def is_calibrated(self) -> bool:
        return True

    def connect(self, calibrate: bool = True) -> None:
        if self.is_connected:
            raise DeviceAlreadyConnectedError(f"{self} is already connected")
        self._world = self._build()

    def calibrate(self) -> None:
        pass

    def configure(self) -> None:
        pass

    def _require(self) -> Any:
        if self._world is None:
            raise DeviceNotConnectedError(f"{self} is not connected; call connect() first")
        return self._world

    def disconnect(self) -> None:
        self._require()
        self._world = None
