"""The LoCoBot wire format, the one module both host and client use. Every message carries `v` = VERSION.

The host binds three ZMQ sockets on one interface; the client connects to them:
- command (client PUSH -> host PULL, CONFLATE: only the latest command is kept), one JSON message:
  {"v", "session", "kind": "step", "step": n, "command": "forward"|"turn_left"|"turn_right"|"stop", "amount"}
  or {"v", "session", "kind": "velocity", "x": m/s, "theta": rad/s}.
- observation (host PUB -> client SUB, CONFLATE on both: a client always reads the newest one, never a
  backlog), one message: a 4-byte big-endian header length, the JSON header {"v", "epoch", "seq", "time",
  "state": {...}, "ack": {"session", "step", "result"}, "frames": [[name, length], ...]}, then the frames
  back to back: "rgb" as JPEG, "depth" as a 16-bit PNG of millimetres.
- rpc (client REQ -> host REP), JSON requests {"v", "op", ...} answered by {"ok": true, ...} or
  {"ok": false, "error": "one line"}. Ops: hello, read_scene, stage_scene, set_odometry.

Discrete steps execute exactly once although commands may be lost, repeated, reordered or conflated: the client
numbers them 1, 2, ... per session and resends step n until an observation acknowledges it; the host starts
step n only when n - 1 has finished (StepGate) and acknowledges the last finished step in every header."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np

VERSION = 1
DEFAULT_PORTS = {"command": 5555, "observation": 5556, "rpc": 5557}
STEP_RESULTS = ("done", "aborted", "timeout", "blocked")


class ProtocolError(ValueError):
    """A message that does not follow this wire format (wrong version, malformed JSON or frames)."""


def encode(message: dict[str, Any]) -> bytes:
    return json.dumps({"v": VERSION, **message}, separators=(",", ":")).encode()


def decode(data: bytes) -> dict[str, Any]:
    try:
        message = json.loads(data)
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise ProtocolError(f"malformed message: {error}") from None
    if not isinstance(message, dict):
        raise ProtocolError("malformed message: not a JSON object")
    if message.get("v") != VERSION:
        raise ProtocolError(
            f"protocol version {message.get('v')!r} but this side speaks {VERSION}; install the same "
            "lerobot_robot_locobot version on the robot and the workstation"
        )
    return message


def encode_frames(rgb: np.ndarray, depth: np.ndarray | None, jpeg_quality: int = 90) -> dict[str, bytes]:
    """JPEG of an RGB image, and a 16-bit PNG of a depth image (metres in, millimetres on the wire)."""
    frames = {"rgb": _jpeg(rgb, jpeg_quality)}
    if depth is not None:
        frames["depth"] = _png_depth(depth)
    return frames


def observation_message(header: dict[str, Any], frames: dict[str, bytes]) -> bytes:
    head = encode({**header, "frames": [[name, len(data)] for name, data in frames.items()]})
    return b"".join([len(head).to_bytes(4, "big"), head, *frames.values()])


def decode_observation(data: bytes) -> tuple[dict[str, Any], dict[str, bytes]]:
    """The header and the still-encoded image frames by name (decode only the images you keep)."""
    size = int.from_bytes(data[:4], "big")
    if len(data) < 4 + size:
        raise ProtocolError("truncated observation message")
    header = decode(data[4 : 4 + size])
    frames, offset = {}, 4 + size
    for name, length in header.get("frames", []):
        frames[name] = data[offset : offset + length]
        offset += length
    if offset != len(data):
        raise ProtocolError(f"observation frames add up to {offset} bytes but the message has {len(data)}")
    return header, frames


def decode_rgb(data: bytes) -> np.ndarray:
    image = cv2.imdecode(np.frombuffer(data, dtype=np.uint8), cv2.IMREAD_COLOR)
    if image is None:
        raise ProtocolError("observation RGB frame is not a JPEG image")
    return cv2.cvtColor(image, cv2.COLOR_BGR2RGB)


def decode_depth(data: bytes) -> np.ndarray:
    image = cv2.imdecode(np.frombuffer(data, dtype=np.uint8), cv2.IMREAD_UNCHANGED)
    if image is None or image.dtype != np.uint16:
        raise ProtocolError("observation depth frame is not a 16-bit PNG image")
    return image.astype(np.float32) / 1000.0


def _jpeg(rgb: np.ndarray, quality: int) -> bytes:
    ok, data = cv2.imencode(".jpg", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, quality])
    if not ok:
        raise ProtocolError("could not JPEG-encode the camera image")
    return data.tobytes()


def _png_depth(depth: np.ndarray) -> bytes:
    millimetres = np.clip(np.rint(np.nan_to_num(depth, nan=0.0) * 1000.0), 0, 65535).astype(np.uint16)
    ok, data = cv2.imencode(".png", millimetres, [cv2.IMWRITE_PNG_COMPRESSION, 1])
    if not ok:
        raise ProtocolError("could not PNG-encode the depth image")
    return data.tobytes()


@dataclass
class StepGate:
    """The host's record of one session's discrete steps: which finished, which runs, what to acknowledge."""

    done: int = 0  # the last finished step
    running: int | None = None
    result: str = "done"  # the result of step `done`

    def offer(self, step: int) -> bool:
        """True when `step` should start now: it is the next one and nothing else is running. Repeats and
        stale or early steps return False, so each step starts exactly once."""
        if self.running is None and step == self.done + 1:
            self.running = step
            return True
        return False

    def finish(self, result: str) -> None:
        if self.running is not None:
            self.done, self.running, self.result = self.running, None, result

    def ack(self, session: str) -> dict[str, Any]:
        return {"session": session, "step": self.done, "result": self.result}


def address(host: str, port: int) -> str:
    return f"tcp://{host}:{port}"
