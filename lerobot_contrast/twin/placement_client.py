"""The one client of the twin's placement socket (twin/placement.py): what the scripted person, the demonstrator,
`python -m lerobot_contrast.twin.place`, the studies and the tests send to the running twin. It reads the twin's
truth, so nothing that stages or labels from the camera uses it."""

from __future__ import annotations

from typing import Any

from lerobot_contrast.clock.simulated import NoAnswer, Requests
from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.contrast.scene import Pose, Scene

HOST = "127.0.0.1"
DEFAULT_PORT = 5556
DEFAULT_ADDRESS = f"tcp://{HOST}:{DEFAULT_PORT}"


class TwinError(UserError):
    """The twin did not answer, or refused a request; one line."""


class PlacementClient:
    """Requests to the twin at `address`, each answered within `timeout_s` or a TwinError saying no twin answers."""

    def __init__(self, address: str = DEFAULT_ADDRESS, timeout_s: float = 5.0) -> None:
        self.address = address
        self._requests = Requests(address, timeout_s, "placement")

    def ask(self, request: dict[str, Any], check: bool = True) -> dict[str, Any]:
        """The twin's reply; with `check`, a refusal is a TwinError naming the request."""
        try:
            reply = self._requests.ask(request)
        except NoAnswer as error:
            raise TwinError(str(error)) from None
        if check and not reply.get("ok"):
            raise TwinError(f"the twin refused {request}: {reply.get('error')}")
        return reply

    def place(self, name: str, x: float, y: float, yaw: float | None = None) -> dict[str, Any]:
        request = {"cmd": "place", "object": name, "x": float(x), "y": float(y)}
        if yaw is not None:
            request["yaw"] = float(yaw)
        return self.ask(request)

    def scene(self) -> Scene:
        return self.look()[0]

    def look(self) -> tuple[Scene, dict[str, float], frozenset[str]]:
        """The true scene, each object's height (m) and the objects touching the gripper's jaws: what tells an object
        resting (on the table, or on another object) from one held in the gripper."""
        reply = self.ask({"cmd": "scene"})
        scene = Scene({name: Pose(*pose) for name, pose in reply["objects"].items()})
        return scene, reply["z"], frozenset(reply["gripped"])

    def time(self) -> float:
        """The twin's simulated time (s): real time on the wall clock (lagging it on a busy machine), the time its
        clients advanced it on the simulated one."""
        return float(self.ask({"cmd": "scene"})["time"])

    def poses(self) -> dict[str, tuple[float, float, float, float]]:
        """Each object's (x, y, z, yaw), as the demonstrator plans from them."""
        reply = self.ask({"cmd": "scene"})
        return {name: (x, y, reply["z"][name], yaw) for name, (x, y, yaw) in reply["objects"].items()}

    def close(self) -> None:
        self._requests.close()


def request(command: dict[str, Any], port: int = DEFAULT_PORT, timeout_s: float = 5.0) -> dict[str, Any]:
    """One command to the twin on `port` of 127.0.0.1, and its reply as sent (a refusal included)."""
    client = PlacementClient(f"tcp://{HOST}:{port}", timeout_s)
    try:
        return client.ask(command, check=False)
    finally:
        client.close()
