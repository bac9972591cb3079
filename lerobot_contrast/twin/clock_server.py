"""The twin's simulated clock (`python -m lerobot_contrast.twin --clock=sim`): nothing in the world moves until a
client asks, and then by exactly the time asked for. A ZMQ REP socket on 127.0.0.1 (replies as the placement
socket's, twin/reply_server.py):

  {"cmd": "time"}                      -> {"time": s}: the world's instant, seconds since the twin started
  {"cmd": "advance", "seconds": s, "frame": bool}
                                       -> {"time": s, "frame": crc or null}: every servo command sent to the bus
                                          before the request takes effect, the servos and the physics step on by
                                          `seconds`, and, where a frame instant of the camera passed, the frame of
                                          the new instant is published before the reply; "frame" is the CRC-32 of
                                          its pixels as LeRobot's camera decodes them (the client waits for it).
                                          With "frame": false (nothing reads the camera before the next advance,
                                          as while the arm moves itself) no frame is drawn.

Simulators that robot software is tested against keep time this way (Gazebo's /clock, MuJoCo's mj_step): a session
runs as fast as the machine allows and gives the same result however busy the machine is."""

from __future__ import annotations

import math
from typing import Any

from lerobot_contrast.twin.physics import CONTROL_DT, Physics
from lerobot_contrast.twin.reply_server import ReplyServer, RequestError, number

DEFAULT_CLOCK_PORT = 5557
MAX_ADVANCE_S = 600.0  # one request's most: longer is a client's mistake (milliseconds for seconds, say)
COMMANDS = ("time", "advance")


class ClockServer(ReplyServer):
    """Steps `physics` (whose servo bank the bus serves, `drain()` answering every command first) and publishes
    `camera`'s frames (a CameraServer started unpaced, or None) at `fps` of simulated time."""

    what, flag = "clock port", "--clock_port"

    def __init__(self, physics: Physics, bus: Any, camera: Any, fps: float, port: int = DEFAULT_CLOCK_PORT) -> None:
        super().__init__(port)
        self.physics, self.bus, self.camera, self.fps = physics, bus, camera, fps
        self.time = 0.0  # the instant clients asked for, summed exactly: ticks and frames are counted from it
        self.ticks = 0
        self.frames = 0  # the index of the last frame instant published

    def handle(self, request: dict[str, Any]) -> dict[str, Any]:
        command = request.get("cmd")
        if command not in COMMANDS:
            raise RequestError(f'unknown command {command!r} in "cmd"; use one of: {", ".join(COMMANDS)}')
        if command == "time":
            return {"time": self.time}
        seconds = number(request, "seconds")
        if not 0 <= seconds <= MAX_ADVANCE_S:
            raise RequestError(f"advance: 'seconds' must be from 0 to {MAX_ADVANCE_S:g}, got {seconds:g}")
        frame = self.advance(seconds, request.get("frame", True) is not False)
        return {"time": self.time, "frame": frame}

    def advance(self, seconds: float, frame: bool = True) -> int | None:
        """Step the world on by `seconds`; the new frame's CRC where a frame instant passed (and `frame`), else
        None."""
        self.bus.drain()  # the driver's last goals are in the servos before they move
        self.time += seconds
        due = math.floor(self.time / CONTROL_DT + 0.5)
        while self.ticks < due:
            self.physics.tick()
            self.ticks += 1
        instant = math.floor(self.time * self.fps + 1e-6)
        if self.camera is None or not frame or instant <= self.frames:
            return None
        self.frames = instant
        return self.camera.capture(self.time)
