"""`python -m lerobot_contrast.twin.place OBJECT X Y [YAW] [--control_port=5556]`: put one of the running twin's
objects down at (X, Y) metres in the task frame (arm base at the origin, x forward, y to the arm's left), turned YAW
degrees: what a person's hand does on a real bench. `... place scene` prints where every object is."""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence

from lerobot_contrast.contrast.errors import UserError
from lerobot_contrast.twin.placement_client import DEFAULT_PORT, request

USAGE = "usage: python -m lerobot_contrast.twin.place OBJECT X Y [YAW] [--control_port=5556]  (or: place scene)"


def parse(argv: Sequence[str]) -> tuple[dict, int]:
    """The placement command and the twin's control port from the command line."""
    port, words, args = DEFAULT_PORT, [], list(argv)
    while args:
        arg = args.pop(0)
        if arg == "--control_port" and args:  # the `--name value` form LeRobot's commands take too
            arg = f"--control_port={args.pop(0)}"
        if arg.startswith("--control_port="):
            port = _integer(arg.split("=", 1)[1], "--control_port")
        elif arg.startswith("-") and not _is_number(arg):
            raise UserError(f"unknown flag {arg.split('=')[0]}; {USAGE}")
        else:
            words.append(arg)
    if words == ["scene"]:
        return {"cmd": "scene"}, port
    if len(words) not in (3, 4):
        raise UserError(USAGE)
    name, *numbers = words
    x, y, *yaw = (_float(value, label) for value, label in zip(numbers, ("X", "Y", "YAW"), strict=False))
    return {"cmd": "place", "object": name, "x": x, "y": y, "yaw": math.radians(yaw[0] if yaw else 0.0)}, port


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _float(text: str, label: str) -> float:
    if not _is_number(text) or not math.isfinite(float(text)):
        raise UserError(f"{label}={text!r} is not a number; {USAGE}")
    return float(text)


def _integer(text: str, label: str) -> int:
    if not text.isdigit():
        raise UserError(f"{label}={text!r} is not a port number")
    return int(text)


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(f"{USAGE}\n\n{(__doc__ or '').strip()}")
        return 0
    try:
        command, port = parse(argv)
        reply = request(command, port)
    except UserError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    if not reply.get("ok"):
        print(f"error: {reply.get('error')}", file=sys.stderr)
        return 1
    if command["cmd"] == "scene":
        for name, (x, y, yaw) in reply["objects"].items():
            print(f"{name}: x={x:.3f} y={y:.3f} m, yaw {math.degrees(yaw):.0f} deg")
    else:
        print(f"placed {command['object']} at x={command['x']:.3f} y={command['y']:.3f} m, yaw "
              f"{math.degrees(command['yaw']):.0f} deg")  # fmt: skip
        if reply.get("moved_aside"):
            print(f"moved out of the way, back where they wait: {', '.join(reply['moved_aside'])}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
