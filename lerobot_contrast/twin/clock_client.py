"""The client of the twin's simulated clock (twin/clock_server.py): `sleep` advances the twin's world, and returns
once the frame of the new instant is the one LeRobot's camera holds, so what the policy sees next is that instant
whatever the machine's load."""

from __future__ import annotations

import sys
import threading
import time
from typing import Any

from lerobot_contrast.twin.camera_server import pixels_crc
from lerobot_contrast.twin.placement_client import PlacementClient, TwinError

FRAME_WAIT_S = 10.0  # wall seconds for a published frame to reach LeRobot's camera thread before it is said late
CONNECT_TIMEOUT_S = 5.0  # wall seconds for the twin's clock to answer at all
ADVANCE_TIMEOUT_S = 120.0  # wall seconds an advance may take (a busy machine steps slowly, but it steps)
FRAME_POLL_S = 0.001
LOOK_S = 1 / 30  # what `look` lets pass: one frame period of the twin's camera at the SO-101's rate


class SimClock:
    """The simulated clock at `address` (tcp://HOST:PORT, as the twin printed it)."""

    simulated = True

    def __init__(self, address: str) -> None:
        self.address = address
        self._twin = PlacementClient(address, CONNECT_TIMEOUT_S, what="clock")
        self._lock = threading.Lock()  # one request at a time: a REQ socket is not shared between threads
        self._cameras: list[Any] = []
        self.late_frames = 0  # advances after which the camera did not show the new frame in FRAME_WAIT_S
        try:
            self._time = float(self._ask({"cmd": "time"})["time"])
        except TwinError:
            raise TwinError(
                f"--clock={address}: no twin's clock answers there; start one with `python -m lerobot_contrast.twin "
                "--clock=sim` and give the clock address it printed, or leave --clock out for real time"
            ) from None
        self._twin.timeout_s = ADVANCE_TIMEOUT_S

    def _ask(self, request: dict) -> dict:
        with self._lock:
            return self._twin.ask(request)

    def now(self) -> float:
        return self._time

    def sleep(self, seconds: float, watched: bool = True) -> None:
        if seconds <= 0:
            return
        reply = self._ask({"cmd": "advance", "seconds": float(seconds), "frame": watched})
        self._time = float(reply["time"])
        if reply.get("frame") is not None:
            for camera in self._cameras:
                self._wait_for(camera, int(reply["frame"]))

    def look(self) -> None:
        self.sleep(LOOK_S)

    def watch(self, robot: Any) -> None:
        """Wait, after each advance, for `robot`'s cameras that LeRobot feeds from the twin (ZMQ) to hold the new
        frame."""
        cameras = getattr(robot, "cameras", None) or {}
        self._cameras = [camera for camera in cameras.values() if hasattr(camera, "latest_frame")]

    def _wait_for(self, camera: Any, crc: int) -> None:
        deadline, looked_at = time.monotonic() + FRAME_WAIT_S, None
        while time.monotonic() < deadline:
            with camera.frame_lock:
                frame, captured = camera.latest_frame, camera.latest_timestamp
            if captured != looked_at and frame is not None:  # each frame the camera's thread captured, once
                looked_at = captured
                if pixels_crc(frame) == crc:
                    return
            time.sleep(FRAME_POLL_S)
        self.late_frames += 1
        print(f"{camera}: the twin's frame at {self._time:.3f} s did not reach the camera within {FRAME_WAIT_S:g} s; "
              "what reads it next may see the frame before", file=sys.stderr, flush=True)  # fmt: skip
