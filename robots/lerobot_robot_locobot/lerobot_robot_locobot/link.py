"""The client end of the wire protocol: handshake, exactly-once discrete steps, velocity commands, the newest
observation, and remote calls. A host restart between steps is picked up transparently (a new handshake)."""

from __future__ import annotations

import contextlib
import time
import uuid
from dataclasses import dataclass
from typing import Any

import zmq

from lerobot_robot_locobot.config_locobot import LocobotConfig
from lerobot_robot_locobot.protocol import ProtocolError, address, decode, decode_observation, encode

# While waiting for a step to be acknowledged, the command is sent again this often (it may have been lost).
RESEND_S = 0.05
# An observation is fresh while it is younger than this many of the host's publishing periods.
FRESH_PERIODS = 3
# Without --robot.observation_timeout_s, a host silent for this many of its publishing periods is gone.
LOST_PERIODS = 60


class LocobotConnectionError(ConnectionError):
    """The host cannot be reached or stopped answering; the message names its address and what to check."""


class LocobotHostError(RuntimeError):
    """The host refused a request (the message is the host's one-line reason)."""


@dataclass(frozen=True)
class Received:
    header: dict[str, Any]
    frames: dict[str, bytes]
    at: float  # time.monotonic() when the host published it

    @property
    def seq(self) -> int:
        return int(self.header["seq"])


class HostLink:
    def __init__(self, config: LocobotConfig) -> None:
        self.config = config
        self.session = uuid.uuid4().hex
        self.context = zmq.Context()
        self.epoch: str | None = None
        self.capabilities: frozenset[str] = frozenset()
        self.step_id = 0
        self.latest: Received | None = None
        self._fresh_from = 0  # the next observation must have at least this seq (after a remote call)
        self._running: int | None = None
        self._max_age = 0.1
        self.lost_after_s = 2.0  # set from the host's publishing rate by the handshake
        self._heard = time.monotonic()  # when the last observation arrived
        self._clock_offset = float("inf")
        try:
            self._command = self._socket(zmq.PUSH, config.port_command, conflate=True)
            self._observation = self._socket(zmq.SUB, config.port_observation, conflate=True)
            self._rpc = self._socket(zmq.REQ, config.port_rpc)
            self.hello()
        except BaseException:
            self.close()
            raise

    def _socket(self, kind: int, port: int, conflate: bool = False) -> zmq.Socket:
        socket = self.context.socket(kind)
        socket.linger = 0
        if conflate:
            socket.setsockopt(zmq.CONFLATE, 1)
        if kind == zmq.SUB:
            socket.setsockopt(zmq.SUBSCRIBE, b"")
        if kind == zmq.REQ:  # a request that timed out may be followed by a new one, replies matched by id
            socket.setsockopt(zmq.REQ_RELAXED, 1)
            socket.setsockopt(zmq.REQ_CORRELATE, 1)
        if self.config.client_secret_key is not None and self.config.server_public_key is not None:
            # Imported here so that importing the package leaves `python -m lerobot_robot_locobot.keys` clean.
            from lerobot_robot_locobot.keys import secure_client

            flags = ("--robot.client_secret_key", "--robot.server_public_key")
            secure_client(socket, self.config.client_secret_key, self.config.server_public_key, flags)
        socket.connect(address(self.config.host, port))
        return socket

    def hello(self) -> None:
        camera = {
            "width": self.config.camera_width,
            "height": self.config.camera_height,
            "depth": self.config.use_depth,
        }
        reply = self.call("hello", timeout_s=self.config.connect_timeout_s, camera=camera)
        self.epoch, self.step_id = reply["epoch"], int(reply["last_step"])
        self.capabilities = frozenset(reply["capabilities"])
        self._fresh_from = int(reply["seq"])  # sequence numbers start afresh in each host process
        self._max_age = FRESH_PERIODS / float(reply["publish_hz"])
        timeout = self.config.observation_timeout_s
        self.lost_after_s = LOST_PERIODS / float(reply["publish_hz"]) if timeout is None else timeout
        self._heard = time.monotonic()

    def call(self, op: str, timeout_s: float | None = None, **fields: Any) -> dict[str, Any]:
        """A remote call; its effects show in every observation from the reply's `seq` on."""
        timeout_s = self.config.connect_timeout_s if timeout_s is None else timeout_s
        self._rpc.send(encode({"op": op, "session": self.session, **fields}))
        if not self._rpc.poll(int(timeout_s * 1000)):
            where = address(self.config.host, self.config.port_rpc)
            raise LocobotConnectionError(
                f"no answer from the LoCoBot host at {where} within {timeout_s:g} s: is `python -m "
                "lerobot_robot_locobot.host` running there with that --bind address and port, and if it uses "
                "CurveZMQ keys, are --robot.client_secret_key and --robot.server_public_key keys it accepts?"
            )
        reply = decode(self._rpc.recv())
        if not reply.get("ok"):
            raise LocobotHostError(str(reply.get("error", "the host refused the request")))
        self._fresh_from = max(self._fresh_from, int(reply.get("seq", 0)))
        return reply

    def step(self, command: str, amount: float) -> Received:
        """Run one discrete step and return the first observation taken after it finished."""
        self.observation()  # a host that restarted since the last observation is met here, not mid-step
        self.step_id += 1
        step = self.step_id
        message = encode({"session": self.session, "kind": "step", "step": step, "command": command, "amount": amount})
        deadline = time.monotonic() + self.config.step_timeout_s
        self._running = step
        try:
            while not self._acknowledged(step):
                where = address(self.config.host, self.config.port_command)
                if time.monotonic() - self._heard > self.lost_after_s:  # a dead host is not waited for to the end
                    raise LocobotConnectionError(
                        f"the LoCoBot host at {where} fell silent during step {step} ({command}): no observation "
                        f"for {self.lost_after_s:g} s"
                    )
                if time.monotonic() > deadline:
                    raise LocobotConnectionError(
                        f"the LoCoBot host at {where} did not finish step {step} ({command}) within "
                        f"{self.config.step_timeout_s:g} s"
                    )
                self._send(message)
                self.poll(int(RESEND_S * 1000))
        finally:
            self._running = None
        assert self.latest is not None
        return self.latest

    def velocity(self, x: float, theta: float) -> None:
        self._send(encode({"session": self.session, "kind": "velocity", "x": x, "theta": theta}))

    def observation(self) -> Received:
        """The newest observation: one the host published within the last few publishing periods and after
        the last remote call took effect, waiting up to the observation timeout for it."""
        self.poll(0)  # take what has arrived; wait only when it is not fresh
        deadline = time.monotonic() + self.lost_after_s
        while self.latest is None or self.latest.seq < self._fresh_from or self._stale():
            if time.monotonic() > deadline:
                raise LocobotConnectionError(
                    f"no observation from the LoCoBot host at {address(self.config.host, self.config.port_observation)} "
                    f"for {self.lost_after_s:g} s"
                )
            self.poll(int(RESEND_S * 1000))
        return self.latest

    def poll(self, timeout_ms: int) -> None:
        """Take the newest observation off the socket, if one arrives within `timeout_ms`."""
        if not self._observation.poll(timeout_ms):
            return
        while True:
            try:
                data = self._observation.recv(zmq.NOBLOCK)
            except zmq.Again:
                return
            self._heard = time.monotonic()
            try:
                header, frames = decode_observation(data)
            except ProtocolError:
                continue
            if header.get("epoch") != self.epoch:
                self._host_restarted()
                continue
            if self.latest is None or int(header["seq"]) > self.latest.seq:
                self.latest = Received(header, frames, time.monotonic() - self._age(float(header["time"])))

    def close(self) -> None:
        self.context.destroy(linger=0)

    def _acknowledged(self, step: int) -> bool:
        ack = None if self.latest is None else self.latest.header.get("ack")
        return ack is not None and ack.get("session") == self.session and int(ack.get("step", 0)) >= step

    def _age(self, published: float) -> float:
        """How long ago the host published at its wall-clock time `published`. The clocks of robot and
        workstation need not agree: the smallest delay seen so far is taken as the offset plus transit time."""
        delay = time.time() - published
        self._clock_offset = min(self._clock_offset, delay)
        return delay - self._clock_offset

    def _stale(self) -> bool:
        return self.latest is not None and time.monotonic() - self.latest.at > self._max_age

    def _send(self, message: bytes) -> None:
        with contextlib.suppress(zmq.Again):  # no connection yet: the resend loop or the next call tries again
            self._command.send(message, zmq.NOBLOCK)

    def _host_restarted(self) -> None:
        """An observation from another host process: shake hands with it, unless a step was under way there."""
        running = self._running
        epoch = self.epoch
        self.hello()
        if self.epoch == epoch:  # a stray message from the old process: nothing changed
            return
        self.latest = None
        if running is not None:
            raise LocobotConnectionError(
                f"the LoCoBot host at {address(self.config.host, self.config.port_rpc)} restarted during step "
                f"{running}; the robot may have moved partly: check it before continuing"
            )
