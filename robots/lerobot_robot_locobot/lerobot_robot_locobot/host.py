"""`python -m lerobot_robot_locobot.host`: runs on the robot (or beside the simulator) and serves one client.

It listens on one interface only, starts each discrete step exactly once, stops the base when commands stop
coming (watchdog), clamps what a client asks for, and publishes observations with the last finished step."""

from __future__ import annotations

import logging
import math
import sys
import threading
import time
import uuid
from typing import Any

import zmq
from navigation_protocol import COMMANDS

from lerobot_robot_locobot.actions import clamp
from lerobot_robot_locobot.backend import Backend, make_backend
from lerobot_robot_locobot.config_host import HostConfig, HostConfigError, parse_config, validate
from lerobot_robot_locobot.keys import KeyFileError, secure_server, start_authenticator
from lerobot_robot_locobot.odometry import OdometryFrame
from lerobot_robot_locobot.protocol import (
    ProtocolError,
    StepGate,
    address,
    decode,
    encode,
    encode_frames,
    observation_message,
)

log = logging.getLogger("lerobot_robot_locobot.host")
# While the base moves, the loop runs at least this often, so closed-loop motions get fresh odometry.
MOTION_PERIOD_S = 0.01


class Host:
    def __init__(self, config: HostConfig, backend: Backend | None = None) -> None:
        validate(config)
        self.config = config
        self.context = zmq.Context()
        self.auth = None
        try:
            if config.server_secret_key is not None:
                self.auth = start_authenticator(self.context, config.authorized_keys, "--authorized_keys")
            self.command, port_command = self._bind(zmq.PULL, config.port_command, conflate=True)
            self.observation, port_observation = self._bind(zmq.PUB, config.port_observation, conflate=True)
            self.rpc, port_rpc = self._bind(zmq.REP, config.port_rpc)
            self.backend = backend or make_backend(config.backend, config)
        except BaseException:
            self._release()
            raise
        self.ports = {"command": port_command, "observation": port_observation, "rpc": port_rpc}
        self.epoch, self.seq = uuid.uuid4().hex, 0
        self.session: str | None = None
        self.gate = StepGate()
        self.frame = OdometryFrame()
        self.last_command = -math.inf
        self._frames: tuple[Any, dict[str, bytes]] | None = None

    def _bind(self, kind: int, port: int, conflate: bool = False) -> tuple[zmq.Socket, int]:
        socket = self.context.socket(kind)
        socket.linger = 0
        if conflate:
            socket.setsockopt(zmq.CONFLATE, 1)
        if self.config.server_secret_key is not None:
            secure_server(socket, self.config.server_secret_key, "--server_secret_key")
        try:
            if port == 0:
                return socket, socket.bind_to_random_port(f"tcp://{self.config.bind}")
            socket.bind(address(self.config.bind, port))
        except zmq.ZMQError as error:
            socket.close()
            raise HostConfigError(
                f"cannot listen on {address(self.config.bind, port)} ({error}): is --bind an address of this "
                "machine, and is the port free (another host still running)?"
            ) from None
        return socket, port

    def serve(self, stop: threading.Event | None = None) -> None:
        """Run until `stop` is set (or forever): commands, calls, watchdog, motion, observations."""
        stop = stop or threading.Event()
        poller = zmq.Poller()
        poller.register(self.command, zmq.POLLIN)
        poller.register(self.rpc, zmq.POLLIN)
        last = next_publish = time.monotonic()
        period = 1.0 / self.config.publish_hz
        while not stop.is_set():
            wait = max(0.0, next_publish - time.monotonic())
            events = dict(poller.poll(1000 * (min(wait, MOTION_PERIOD_S) if self.backend.moving else wait)))
            publish = False
            if self.rpc in events:
                publish |= self._serve_rpc()
            if self.command in events:
                publish |= self._serve_command()
            now = time.monotonic()
            publish |= self._watchdog(now)
            result = self.backend.update(now - last)
            last = now
            if result is not None:
                self.gate.finish(result)
                publish = True
            if publish or now >= next_publish:
                self.publish()
                next_publish = now + period

    def publish(self) -> None:
        x, y, theta = self.frame.apply(self.backend.odometry())
        key, rgb, depth = self.backend.images()
        if self._frames is None or self._frames[0] != key:
            self._frames = (key, encode_frames(rgb, depth, self.config.jpeg_quality))
        self.seq += 1
        header = {
            "epoch": self.epoch,
            "seq": self.seq,
            "time": time.time(),
            "state": {"odom.x": x, "odom.y": y, "odom.theta": theta, **self.backend.state()},
            "ack": None if self.session is None else self.gate.ack(self.session),
        }
        self.observation.send(observation_message(header, self._frames[1]), zmq.NOBLOCK)

    def _serve_command(self) -> bool:
        try:
            message = decode(self.command.recv(zmq.NOBLOCK))
        except (zmq.Again, ProtocolError) as error:
            log.debug("command dropped: %s", error)
            return False
        if message.get("session") != self.session or self.session is None:
            return False  # a client that has been replaced, or a stray message
        self.last_command = time.monotonic()
        if message.get("kind") == "step" and message.get("command") in COMMANDS:
            if self.gate.offer(int(message["step"])):
                self.backend.start_step(message["command"], self._amount(message["command"], message.get("amount", 0)))
            return True  # publish now, so a resent step learns at once that it already ran
        if message.get("kind") == "velocity" and self.gate.running is None:
            x, theta = clamp(message["x"], self.config.max_x_vel), clamp(message["theta"], self.config.max_theta_vel)
            self.backend.set_velocity(x, theta)
        return False

    def _amount(self, command: str, amount: float) -> float:
        if command == "forward":
            return clamp(amount, self.config.max_step_m)
        return min(abs(float(amount)), math.radians(self.config.max_turn_deg))

    def _watchdog(self, now: float) -> bool:
        if not self.backend.moving or now - self.last_command <= self.config.watchdog_s:
            return False
        log.warning("no command for %.2f s: stopping the base", now - self.last_command)
        if self.backend.stop():
            self.gate.finish("aborted")
        return True

    def _serve_rpc(self) -> bool:
        """Answer one call; True if it changed what observations show."""
        try:
            request = decode(self.rpc.recv())
            reply, changed = self._call(request)
            reply = {"ok": True, "seq": self.seq + 1, **reply}
        except (ProtocolError, ValueError, KeyError, TypeError, RuntimeError) as error:
            reply, changed = {"ok": False, "error": " ".join(str(error).split())}, False
        self.rpc.send(encode(reply))
        return changed

    def _call(self, request: dict[str, Any]) -> tuple[dict[str, Any], bool]:
        op = request.get("op")
        if op == "hello":
            return self._hello(request), True
        if request.get("session") != self.session:
            raise RuntimeError("another client has taken over this host since you connected; connect again")
        if op == "read_scene":
            return {"scene": self.backend.read_scene()}, False
        if op == "stage_scene":
            self.backend.stop()
            self.backend.stage_scene(request["scene"])
            self.frame.reset()
            return {}, True
        if op == "set_odometry":
            self.frame.set(self.backend.odometry(), tuple(float(v) for v in request["pose"]))
            return {}, True
        raise ValueError(f"unknown request {op!r}")

    def _hello(self, request: dict[str, Any]) -> dict[str, Any]:
        camera = request["camera"]
        width, height = int(camera["width"]), int(camera["height"])
        if not (16 <= width <= 4096 and 16 <= height <= 4096):
            raise ValueError(f"camera size {width}x{height} is out of range (16 to 4096 pixels a side)")
        if request["session"] != self.session:
            log.info("client %s connected", request["session"][:8])
            self.backend.stop()
            self.session, self.gate = request["session"], StepGate()
        self.backend.configure_camera(width, height, bool(camera.get("depth", False)))
        return {
            "epoch": self.epoch,
            "last_step": self.gate.done,
            "capabilities": sorted(self.backend.capabilities),
            "limits": {"x_vel": self.config.max_x_vel, "theta_vel": self.config.max_theta_vel},
            "publish_hz": self.config.publish_hz,
        }

    def close(self) -> None:
        self.backend.close()
        self._release()

    def _release(self) -> None:
        if self.auth is not None:
            self.auth.stop()
        self.context.destroy(linger=0)


class HostThread:
    """A host serving from a background thread: `with HostThread(config) as host: ...` (demos, benchmarks,
    tests). Ports given as 0 are chosen free; `host.ports` tells which."""

    def __init__(self, config: HostConfig, backend: Backend | None = None) -> None:
        self.config, self.backend = config, backend
        self.stop_event = threading.Event()
        self.host: Host | None = None
        self._ready = threading.Event()
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name="locobot-host", daemon=True)

    def _run(self) -> None:
        try:  # sockets are made and used in this thread, as ZMQ requires
            self.host = Host(self.config, self.backend)
        except BaseException as error:
            self._error = error
            self._ready.set()
            return
        self._ready.set()
        try:
            self.host.serve(self.stop_event)
        finally:
            self.host.close()

    def __enter__(self) -> Host:
        self._thread.start()
        self._ready.wait()
        if self._error is not None:
            raise self._error
        assert self.host is not None
        return self.host

    def __exit__(self, *exc: object) -> None:
        self.stop_event.set()
        self._thread.join(timeout=5.0)


def main(argv: list[str] | None = None) -> int:
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(message)s")
    try:
        config = parse_config(sys.argv[1:] if argv is None else argv)
        host = Host(config)
    except (HostConfigError, KeyFileError, ImportError, ValueError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    ports = ", ".join(f"{name} {port}" for name, port in host.ports.items())
    secured = "CurveZMQ" if config.server_secret_key else "no encryption"
    print(f"LoCoBot host ({config.backend} backend) on {config.bind}: {ports}; {secured}. Ctrl-C stops.", flush=True)
    try:
        host.serve()
    except KeyboardInterrupt:
        pass
    finally:
        host.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
