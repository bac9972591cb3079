"""The client of the twin's simulated clock (twin/clock_server.py): `sleep` advances the twin's world, and returns
once the frame of the new instant is the one LeRobot's camera holds, so what the policy sees next is that instant
whatever the machine's load."""

from __future__ import annotations

import json
import sys
import threading
import time
import zlib
from typing import Any

import numpy as np
import zmq

from lerobot_contrast.contrast.errors import UserError

FRAME_WAIT_S = 10.0  # wall seconds for a published frame to reach LeRobot's camera thread before it is said late
CONNECT_TIMEOUT_S = 5.0  # wall seconds for the twin's clock to answer at all
ADVANCE_TIMEOUT_S = 120.0  # wall seconds an advance may take (a busy machine steps slowly, but it steps)
FRAME_POLL_S = 0.001
LOOK_S = 1 / 30  # what `look` lets pass: one frame period of the twin's camera at the SO-101's rate


def pixels_crc(image: np.ndarray) -> int:
    """CRC-32 of an image's pixels: the twin's of a frame it sent, the client's of the frame its camera holds."""
    return zlib.crc32(np.ascontiguousarray(image).data)


class NoAnswer(UserError):
    """The twin did not answer a request; one line."""


class Requests:
    """JSON requests to one of the twin's REP sockets (its placement or its clock) at `address`, each answered within
    `timeout_s` or a `NoAnswer` naming the socket (`what`)."""

    def __init__(self, address: str, timeout_s: float, what: str) -> None:
        self.address, self.timeout_s, self.what = address, timeout_s, what
        self._context = zmq.Context.instance()
        self._socket = self._connect()

    def _connect(self) -> zmq.Socket:
        socket = self._context.socket(zmq.REQ)
        socket.setsockopt(zmq.LINGER, 0)
        socket.connect(self.address)
        return socket

    def ask(self, request: dict[str, Any]) -> dict[str, Any]:
        """The twin's reply as sent (a refusal included)."""
        self._socket.send_string(json.dumps(request))
        if not self._socket.poll(round(self.timeout_s * 1000)):
            self._socket.close()
            self._socket = self._connect()  # a REQ socket that missed its reply cannot send again
            raise NoAnswer(
                f"no twin answers on {self.address} within {self.timeout_s:g} s; start it with "
                f"`python -m lerobot_contrast.twin` or give the {self.what} address it printed"
            )
        return json.loads(self._socket.recv())

    def close(self) -> None:
        self._socket.close()


class SimClock:
    """The simulated clock at `address` (tcp://HOST:PORT, as the twin printed it)."""

    simulated = True

    def __init__(self, address: str) -> None:
        self.address = address
        self._twin = Requests(address, CONNECT_TIMEOUT_S, "clock")
        self._lock = threading.Lock()  # one request at a time: a REQ socket is not shared between threads
        self._cameras: list[Any] = []
        self.late_frames = 0  # advances after which the camera did not show the new frame in FRAME_WAIT_S
        try:
            self._time = float(self._ask({"cmd": "time"})["time"])
        except NoAnswer:
            raise NoAnswer(
                f"--clock={address}: no twin's clock answers there; start one with `python -m lerobot_contrast.twin "
                "--clock=sim` and give the clock address it printed, or leave --clock out for real time"
            ) from None
        self._twin.timeout_s = ADVANCE_TIMEOUT_S

    def _ask(self, request: dict) -> dict:
        with self._lock:
            reply = self._twin.ask(request)
        if not reply.get("ok"):
            raise UserError(f"the twin's clock refused {request}: {reply.get('error')}")
        return reply

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
