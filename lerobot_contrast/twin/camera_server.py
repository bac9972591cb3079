"""Publishes the twin's webcam frames at the control rate in the wire format of LeRobot's `zmq` camera (one JSON
string per message: {"timestamps": {name: seconds}, "images": {name: base64 JPEG}}), so its `ZMQCamera` reads them.
"""

from __future__ import annotations

import base64
import json
import logging
import queue
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np
import zmq

from lerobot_contrast.clock.simulated import pixels_crc
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.twin.camera import CameraArgs, TwinCamera
from lerobot_contrast.twin.lens import LensArgs

logger = logging.getLogger(__name__)

JPEG_QUALITY = 80  # what LeRobot's own image_server sends
CAPTURE_TIMEOUT_S = 60  # a frame the camera's thread has not published by then: that thread is stuck
# Unpaced, the paused instant's frame goes out again this often: well inside the second after which LeRobot's camera
# calls a frame too old, and rarely enough that decoding the repeats costs the client little.
REPEAT_S = 0.25


@dataclass
class FrameTimes:
    """Seconds spent per published frame, summed: rendering (with the lens), JPEG encoding, sending."""

    frames: int = 0
    render_s: float = 0.0
    encode_s: float = 0.0
    send_s: float = 0.0


def encode(name: str, frame: np.ndarray, timestamp: float) -> str:
    """One message of LeRobot's zmq camera protocol. LeRobot's server JPEG-encodes its RGB frames as they are (as
    if BGR) and its `ZMQCamera` decodes without converting, so RGB in gives RGB out; do the same."""
    return message(name, jpeg_of(frame), timestamp)


def jpeg_of(frame: np.ndarray) -> np.ndarray:
    ok, jpeg = cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
    if not ok:
        raise ValueError(f"cannot JPEG-encode a frame of shape {frame.shape}")
    return jpeg


def message(name: str, jpeg: np.ndarray, timestamp: float) -> str:
    return json.dumps({"timestamps": {name: timestamp}, "images": {name: base64.b64encode(jpeg).decode("ascii")}})


class CameraServer:
    """Calls `render()` on its own thread `fps` times a second and publishes each frame on a ZMQ PUB socket;
    `close()` (if given) runs on that thread when it stops, to free what `render` made there (a GL context).

    Unpaced (the simulated clock), it renders only when `capture` asks, and between captures sends the last frame
    again every REPEAT_S: the world is paused, and LeRobot's camera counts a frame older than a second as a dead
    camera's."""

    def __init__(self, render: Callable[[], np.ndarray], name: str = "front", port: int = 5555, fps: float = 30.0,
                 host: str = "127.0.0.1", close: Callable[[], None] | None = None,
                 paced: bool = True) -> None:  # fmt: skip
        if fps <= 0:
            raise UserError(f"--fps={fps:g}: give a positive frame rate (the control rate, 30 for the SO-101)")
        self.render, self.name, self.port, self.fps, self.host, self._close = render, name, port, fps, host, close
        self.paced = paced
        self._requests: queue.Queue = queue.Queue()
        self.times = FrameTimes()
        self.error: str | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._context: zmq.Context | None = None

    @property
    def address(self) -> str:
        return f"tcp://{self.host}:{self.port}"

    def start(self) -> str:
        """Bind the socket (a port in use is one line saying so) and start publishing; returns the address."""
        self._context = zmq.Context()
        socket = self._context.socket(zmq.PUB)
        socket.setsockopt(zmq.SNDHWM, 20)
        socket.setsockopt(zmq.LINGER, 0)
        try:
            socket.bind(self.address)
        except zmq.ZMQError as error:
            socket.close()
            self._context.term()
            raise UserError(
                f"camera port {self.port} on {self.host}: {error.strerror}; choose a free one with --camera_port"
            ) from None
        self._thread = threading.Thread(target=self._run, args=(socket,), name=f"twin camera {self.name}", daemon=True)
        self._thread.start()
        return self.address

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=10)
        if self._context is not None:
            self._context.term()
            self._context = None

    def capture(self, timestamp: float) -> int:
        """(Unpaced) Render the frame of simulated instant `timestamp` on the camera's thread and publish it; returns
        `pixels_crc` of the frame as a JPEG decoder gives it back, which is what the client's camera will hold."""
        done: queue.Queue = queue.Queue(maxsize=1)
        self._requests.put((timestamp, done))
        try:
            result = done.get(timeout=CAPTURE_TIMEOUT_S)
        except queue.Empty:
            raise RuntimeError(f"twin camera {self.name}: no frame within {CAPTURE_TIMEOUT_S} s") from None
        if isinstance(result, Exception):
            raise result
        return result

    def _run(self, socket: zmq.Socket) -> None:
        try:
            (self._paced if self.paced else self._on_request)(socket)
        except Exception as error:  # a dead camera thread must say why, not leave a silent black feed
            self.error = f"twin camera {self.name} stopped: {' '.join(str(error).split())[:200]}"
            print(self.error, file=sys.stderr)
        finally:
            socket.close()
            if self._close is not None:
                self._close()

    def _paced(self, socket: zmq.Socket) -> None:
        period = 1.0 / self.fps
        deadline = time.perf_counter()
        while not self._stop.is_set():
            self._publish(socket, time.time())
            deadline += period
            # Behind schedule (a slow frame): start the next one now rather than sending a burst to catch up.
            deadline = max(deadline, time.perf_counter())
            self._stop.wait(max(0.0, deadline - time.perf_counter()))

    def _on_request(self, socket: zmq.Socket) -> None:
        sent, _ = self._publish(socket, 0.0)  # the first instant's: LeRobot's camera waits for a frame to connect
        while not self._stop.is_set():
            try:
                timestamp, done = self._requests.get(timeout=REPEAT_S)
            except queue.Empty:
                self._send(socket, sent)
                continue
            try:
                sent, jpeg = self._publish(socket, timestamp)
                done.put(pixels_crc(cv2.imdecode(jpeg, cv2.IMREAD_COLOR)))
            except Exception as error:
                done.put(error)
                raise

    def _send(self, socket: zmq.Socket, text: str) -> None:
        try:
            socket.send_string(text, zmq.NOBLOCK)
        except zmq.Again:
            logger.debug("camera %s: send queue full, frame dropped", self.name)

    def _publish(self, socket: zmq.Socket, timestamp: float) -> tuple[str, np.ndarray]:
        """Render, encode and send one frame stamped `timestamp`; returns the message and its JPEG."""
        started = time.perf_counter()
        frame = self.render()
        rendered = time.perf_counter()
        jpeg = jpeg_of(frame)
        text = message(self.name, jpeg, timestamp)
        encoded = time.perf_counter()
        self._send(socket, text)
        sent = time.perf_counter()
        times = self.times
        times.frames += 1
        times.render_s += rendered - started
        times.encode_s += encoded - rendered
        times.send_s += sent - encoded
        return text, jpeg


def serve_camera(read: Callable[[Callable], object], target: tuple[float, float, float], args: CameraArgs,
                 lens: LensArgs, name: str = "front", port: int = 5555, fps: float = 30.0,
                 paced: bool = True) -> CameraServer:  # fmt: skip
    """Start publishing the twin's webcam (`paced`: in real time, else on the simulated clock's request). `read(view)`
    calls `view(model, data)` while the physics holds still (`Physics.read`): only the scene's copy happens then, the
    drawing and the lens after."""
    camera = TwinCamera(target, args, lens)

    def render() -> np.ndarray:
        read(camera.capture)
        return camera.develop()

    server = CameraServer(render, name=name, port=port, fps=fps, close=camera.close, paced=paced)
    server.start()
    return server


def robot_cameras(server: CameraServer, args: CameraArgs) -> str:
    """The value of eval's --robot.cameras that makes LeRobot's `ZMQCamera` read `server`."""
    return (f"{{{server.name}: {{type: zmq, server_address: {server.host}, port: {server.port}, camera_name: "
            f"{server.name}, width: {args.width}, height: {args.height}, fps: {round(server.fps)}}}}}")  # fmt: skip
