"""The twin's placement commands: a ZMQ REP socket on 127.0.0.1 taking one JSON object per request, since no hand can
move the twin's objects. Requests and their replies (all lengths in metres, task frame: arm base at the origin, x
forward, y to the arm's left; every reply has "ok", and "error" with one line when "ok" is false):

  {"cmd": "place", "object": NAME, "x": m, "y": m, "yaw": rad}  put an object down there, at rest (yaw optional)
                                        -> {"moved_aside": [NAME]}: objects in the way, put back where they wait
  {"cmd": "scene"}                       -> {"objects": {NAME: [x, y, yaw]}, "z": {NAME: z}, "gripped": [NAME],
                                           "time": s}: the true poses, the objects touching the gripper's jaws, and
                                           the simulated time (it lags the wall clock on a busy machine)
  {"cmd": "board", "x": m, "y": m, "yaw_deg": deg}  lay the printed calibration board on the table
  {"cmd": "remove_board"}               -> {"removed": bool}
  {"cmd": "reset_arm"}                  put the arm at rest at once
  {"cmd": "close"}                      -> {"closed": true}: answer no more requests (nothing may read the truth)
"""

from __future__ import annotations

import math
from typing import Any

from lerobot_contrast.domains.task_file.schema import TaskSpec
from lerobot_contrast.so101.scene import object_sizes, start_poses, table_extent
from lerobot_contrast.twin.physics import Physics
from lerobot_contrast.twin.placement_client import DEFAULT_PORT
from lerobot_contrast.twin.reply_server import ReplyServer, RequestError, number

COMMANDS = ("place", "scene", "board", "remove_board", "reset_arm", "close")


class PlacementServer(ReplyServer):
    """Answers placement requests for `physics`, whose world was built from `task`, on `port` of 127.0.0.1."""

    what, flag = "control port", "--control_port"

    def __init__(self, physics: Physics, task: TaskSpec, port: int = DEFAULT_PORT) -> None:
        super().__init__(port)
        self.physics, self.task = physics, task
        self.parked = start_poses(task, None)  # where each object waits off the workspace

    def handle(self, request: dict[str, Any]) -> dict[str, Any]:
        command = request.get("cmd")
        if command not in COMMANDS:
            raise RequestError(f'unknown command {command!r} in "cmd"; use one of: {", ".join(COMMANDS)}')
        if command == "scene":
            poses = self.physics.poses()
            return {
                "objects": {name: [x, y, yaw] for name, (x, y, _, yaw) in poses.items()},
                "z": {name: z for name, (_, _, z, _) in poses.items()},
                "gripped": sorted(self.physics.gripped()),
                "time": self.physics.read(lambda model, data: float(data.time)),
            }
        if command == "place":
            return {"moved_aside": self._place(request)}
        if command == "close":
            self._closing = True
            return {"closed": True}
        if command == "board":
            from lerobot_contrast.twin.board import add_board

            x, y, yaw_deg = (number(request, key) for key in ("x", "y", "yaw_deg"))
            self.physics.edit(lambda spec: add_board(spec, x, y, yaw_deg))
        elif command == "remove_board":
            from lerobot_contrast.twin.board import remove_board

            removed = []
            self.physics.edit(lambda spec: removed.append(remove_board(spec)))
            return {"removed": bool(removed and removed[0])}
        else:
            self.physics.reset_arm()
        return {}

    def _place(self, request: dict[str, Any]) -> list[str]:
        name = request.get("object")
        objects = self.task.objects
        if name not in objects:
            raise RequestError(f"unknown object {name!r}; the twin's task {self.task.name} has: {', '.join(objects)}")
        if not objects[name].movable:
            raise RequestError(f"{name} is fixed in the task file (movable: false); it cannot be placed")
        x, y = number(request, "x"), number(request, "y")
        yaw = number(request, "yaw") if "yaw" in request else 0.0
        half = object_sizes(self.task)[name] / 2
        (x0, x1), (y0, y1) = table_extent(self.task)
        if not (x0 + half <= x <= x1 - half and y0 + half <= y <= y1 - half):
            raise RequestError(
                f"({x:.3f}, {y:.3f}) m is off the table, which spans x {x0:.2f} to {x1:.2f} m and y {y0:.2f} to "
                f"{y1:.2f} m (metres, not centimetres)"
            )
        aside = self._in_the_way(name, x, y)
        for other in aside:  # as a hand clears the spot first: an overlap would fling both objects apart
            parked = self.parked[other]
            self.physics.place(other, parked.x, parked.y, parked.yaw)
        self.physics.place(name, x, y, yaw)
        return aside

    def _in_the_way(self, name: str, x: float, y: float) -> list[str]:
        """Objects lying where `name` is to go: closer than their half sizes together, the two would sit deep in each
        other (nearer, a slight overlap is pushed apart gently by the contacts, as a hand would nudge it)."""
        sizes = object_sizes(self.task)
        return [
            other
            for other, (ox, oy, _, _) in self.physics.poses().items()
            if other != name
            and self.task.objects[other].movable
            and math.hypot(ox - x, oy - y) < (sizes[name] + sizes[other]) / 2
        ]
